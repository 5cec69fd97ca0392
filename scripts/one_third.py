#!/usr/bin/env python3
"""The lamp sweep's one-third rule measured with several independent seed pairs.

docs/benchmark.md's rule: on a spiky lamp, a table's error above the floor (``de2``, design
§6.7) is at most a third of the best simple sampler's, wherever that sampler is more than 10 %
above the floor. The benchmark measures each image from one seed pair, whose ``de2`` on the
lamp sweep's small images has a relative standard error of 8-15 %; where the best simple
sampler is within 1.2-2 times the floor, the share above it is then uncertain by 0.1-0.5, so a
single pair cannot say on which side of a third a job lies. This renders each job's rows, floor
and reference as the benchmark does (``wavelength-pdf benchmark --sweep lamps
--wavelength-net``: its scene copies, tables and renders, reused where an OUT already holds
them) with ``--pairs`` K seed pairs (seeds 1..2K; pair 1 is the benchmark's own), and reports
per job and spp the share from the pairs' mean measures with its jackknife standard error
(:func:`wavelength_pdf.evaluation.benchmark.measures.share_above_floor`) and a verdict:
``reached`` (share at most 1/3), ``missed`` (more than two standard errors above 1/3),
``unresolved`` (above 1/3, within two standard errors), or ``nothing to gain`` (the best
simple sampler at most 10 % above the floor). The best simple sampler is chosen by its mean
over the pairs.

    .venv/bin/python scripts/one_third.py -o out/benchmark-net --pairs 8 \\
        --only colorchecker/cie-FL7 cornell-box/2641 --docs docs/benchmark/one-third

Writes OUT/one-third.csv (a row per job, spp and pair-averaged measure) and OUT/one-third.md.
"""
from __future__ import annotations

import argparse
import csv
import io
import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from wavelength_pdf import progress
from wavelength_pdf.evaluation.benchmark import grid as G
from wavelength_pdf.evaluation.benchmark import measures, run
from wavelength_pdf.evaluation.render import temporary
from wavelength_pdf.exr import read_rgb

#: The rows a share is measured for: the image's table (the rule's subject) and J's.
TABLE_ROWS = (G.IMAGE, "optimized")


def jobs(shared: Path, only: list[str] | None, pairs: int) -> list[G.Job]:
    """The lamp sweep's spiky, low-discrepancy jobs (``only``: those whose name starts so), on
    ``--wavelength-net``, with their simple rows and :data:`TABLE_ROWS`, ``pairs`` seed pairs,
    and no check row."""
    spec = G.select(G.select(G.full_grid(shared), ["lamps"]), only)
    spec = G.with_wavelength_net(G.with_rows(spec, [*G.SIMPLE, *TABLE_ROWS]), True)
    return [replace(j, spp=(16, 64), floor_spp=(16, 64), check_spp=(), seeds=tuple(range(1, 2 * pairs + 1)))
            for j in spec.jobs if j.lamp is not None and j.lamp.spiky and j.pixel_sampler == "sobol"]


def pair_measures(p: run.JobPlan) -> dict[tuple[str, int], np.ndarray]:
    """(row or floor, spp) -> the ``de2`` of each seed pair (K,), against the job's reference."""
    _, _, truth = run.reference(p)
    seeds = p.job.seeds
    out = {}
    for n in p.job.spp:
        renders = {row: [p.images[(row, n, s)] for s in seeds] for row in {r for r, m, _ in p.images if m == n}}
        renders[G.FLOOR] = [p.floor[(n, s)] for s in seeds]
        for row, rs in renders.items():
            out[(row, n)] = np.array([measures.pair(read_rgb(a.out), read_rgb(b.out), truth)["de2"]
                                      for a, b in zip(rs[0::2], rs[1::2])])
    return out


def verdicts(p: run.JobPlan, m: dict[tuple[str, int], np.ndarray]) -> list[dict]:
    """A row per spp and table row: the share above the floor of the best simple sampler's,
    its standard error and the verdict (module docstring)."""
    out = []
    for n in p.job.spp:
        floor = m[(G.FLOOR, n)]
        simple = {r: m[(r, n)] for r in G.SIMPLE if (r, n) in m}
        best = min(simple, key=lambda r: simple[r].mean())
        s, f = simple[best], floor
        for row in TABLE_ROWS:
            if (row, n) not in m:
                continue
            share, se = measures.share_above_floor(m[(row, n)], s, f)
            if not s.mean() > 1.1 * f.mean():
                verdict = "nothing to gain"
            elif share <= 1 / 3:
                verdict = "reached"
            else:
                verdict = "missed" if share - 2 * se > 1 / 3 else "unresolved"
            out.append({"job": p.job.name, "lamp": p.job.lamp_key, "kind": p.job.lamp.kind, "spp": n, "row": row,
                        "pairs": len(f), "best_simple": best, "best_over_floor": s.mean() / f.mean(),
                        "de2": m[(row, n)].mean(), "de2_best": s.mean(), "de2_floor": f.mean(),
                        "share": share, "share_se": se, "verdict": verdict})
    return out


def markdown(rows: list[dict], command: str) -> str:
    lines = ["# The one-third rule with several seed pairs", "", f"    {command}", "",
             "Share: the row's `de2` above the floor over the best simple sampler's (pair means); "
             "se: jackknife over the pairs.", ""]
    for row in TABLE_ROWS:
        sub = [r for r in rows if r["row"] == row]
        if not sub:
            continue
        lines += [f"## {row}", ""]
        for n in sorted({r["spp"] for r in sub}):
            at = [r for r in sub if r["spp"] == n]
            count = {v: sum(r["verdict"] == v for r in at) for v in ("reached", "unresolved", "missed",
                                                                     "nothing to gain")}
            lines.append(f"- {n} spp, {len(at)} jobs: " + ", ".join(f"{v} {c}" for v, c in count.items()))
        lines += ["", "| job | spp | pairs | best simple | best / floor | share | se | verdict |",
                  "|---|---|---|---|---|---|---|---|"]
        lines += [f"| {r['job']} | {r['spp']} | {r['pairs']} | {r['best_simple']} | {r['best_over_floor']:.2f} | "
                  f"{r['share']:.2f} | {r['share_se']:.2f} | {r['verdict']} |" for r in sub]
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("-o", "--outdir", type=Path, default=Path("out/benchmark-net"),
                    help="the benchmark's folder for --wavelength-net runs (default out/benchmark-net)")
    ap.add_argument("--pairs", type=int, default=8, metavar="K", help="seed pairs per image, >= 2 (default 8)")
    ap.add_argument("--only", nargs="+", default=None, metavar="PREFIX",
                    help="only the jobs whose name starts so (default: every spiky lamp on both scenes)")
    ap.add_argument("--shared", type=Path, default=G.SHARED, help=f"the shared material (default {G.SHARED})")
    ap.add_argument("--workers", type=int, default=None, help="Dask worker processes (default: one per core)")
    ap.add_argument("--pbrt", type=Path, default=None, help="the renderer (default: as design §7)")
    ap.add_argument("--docs", type=Path, default=None, metavar="DIR", help="also copy the CSV and the page to DIR")
    args = ap.parse_args(argv)
    if args.pairs < 2:
        ap.error(f"--pairs must be at least 2 (a standard error needs two), not {args.pairs}")
    from wavelength_pdf.renderer import find_pbrt

    find_pbrt(args.pbrt)
    todo = jobs(args.shared, args.only, args.pairs)
    if not todo:
        print(f"one_third.py: no spiky lamp-sweep job matches {args.only} under {args.shared}", file=sys.stderr)
        return 2
    plans = [run.plan_job(j, args.outdir, args.shared, args.pbrt) for j in todo]
    run.run(plans, workers=args.workers, out=args.outdir, shared=args.shared, pbrt=args.pbrt)
    rows = []
    with progress.bar(total=len(plans), desc="scoring", file=sys.stderr, unit="job") as bar:
        for p in plans:
            rows += verdicts(p, pair_measures(p))
            bar.update(1)
    command = "scripts/one_third.py " + " ".join(argv if argv is not None else sys.argv[1:])
    table = io.StringIO(newline="")
    w = csv.DictWriter(table, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    page = markdown(rows, command)
    texts = {"one-third.csv": table.getvalue(), "one-third.md": page + "\n"}
    for folder in [args.outdir] + ([args.docs] if args.docs is not None else []):
        folder.mkdir(parents=True, exist_ok=True)
        for name, text in texts.items():
            # Through a temporary file beside it: an interrupted run leaves the earlier file.
            tmp = temporary(folder / name)
            tmp.write_text(text, encoding="utf-8")
            os.replace(tmp, folder / name)
    print(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
