"""What ``pbrt --wavelength-net`` buys (design §5.2, docs/benchmark.md "The wavelength number
drawn with the film position and the light"): the same renders with and without it.

Two kinds of case, each rendered at one spp with PAIRS seed pairs, one render at a time, the
two alternating seed by seed:

- ``--benchmark OUT``: the benchmark's jobs under OUT (``wavelength-pdf benchmark`` wrote them:
  OUT/jobs/SCENE/LAMP/PIXEL-SAMPLER/scene.pbrt at the benchmark's size, the lamp's tables in
  OUT/tables/LAMP), for each of ``--rows`` (the lamp's tables, e.g. ``spd``, the emission
  switch's table, and ``optimized``), selected by ``--only``;
- ``--scenes``: the project's benchmark scenes with their own lamps (scenes/benchmark), at
  ``--size``, with emission sampling (``--wavelength-sampling emission``) and wavelength
  guiding (``--wavelength-guiding``).

The error is the benchmark's ``de2`` (the mean over the lit pixels of CIEDE2000(A, B)^2 / 2 of a
seed pair) and ``mean_de`` (the pairs' mean ΔE00 over sqrt(2)); the CSV gives both with and
without the net, their ratios (below 1: the net is better) at equal spp and at equal CPU time
(``renderCPUSeconds``; a squared error falls as 1/spp, ΔE00 as spp^-1/2), and the CPU seconds.

    .venv/bin/python scripts/measure_wavelength_net.py --benchmark out/benchmark --only colorchecker/ \\
        --rows spd optimized --spp 64 --pairs 1 --out docs/benchmark/wavelength-net-colorchecker.csv
    .venv/bin/python scripts/measure_wavelength_net.py --scenes night-street window-room lamp-room \\
        --size 320 240 --spp 64 --pairs 3 --out docs/benchmark/wavelength-net-scenes.csv
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "python"))

from wavelength_pdf.evaluation.benchmark import grid as G  # noqa: E402
from wavelength_pdf.evaluation.benchmark.measures import _delta_e, equal_time_ratio, lit_pixels  # noqa: E402
from wavelength_pdf.evaluation.metrics import rgb_to_lab  # noqa: E402
from wavelength_pdf.evaluation.scene_edit import edit_scene  # noqa: E402
from wavelength_pdf.exr import read_header, read_rgb  # noqa: E402

NET = ("--wavelength-net",)
SCENE_SAMPLERS = {"emission": ("--wavelength-sampling", "emission"), "guided": ("--wavelength-guiding",)}


def cases(a: argparse.Namespace, tmp: Path) -> list[tuple[str, str, str, Path, tuple[str, ...]]]:
    """(case, kind, sampler, scene, sampler's flags) of everything to measure; exits naming what
    is missing before any render."""
    out, missing = [], []
    if a.benchmark is not None:
        jobs = sorted(p.parent for p in (a.benchmark / "jobs").glob("*/*/*/scene.pbrt"))
        jobs = [j for j in jobs if not a.only or any(str(j.relative_to(a.benchmark / "jobs")).startswith(o)
                                                     for o in a.only)]
        if not jobs:
            missing.append(f"no benchmark job under {a.benchmark / 'jobs'}" +
                           (f" starting with {' or '.join(a.only)}" if a.only else ""))
        for j in jobs:
            scene_key, lamp, _ = j.relative_to(a.benchmark / "jobs").parts
            kind = G.LAMPS[lamp].kind if lamp in G.LAMPS else "own"
            for row in a.rows:
                table = a.benchmark / "tables" / lamp / f"{row}.csv"
                if not table.is_file():
                    missing.append(f"{j}: no {row} table {table}")
                    continue
                out.append((f"{scene_key}/{lamp}", kind, row, j / "scene.pbrt", ("--wavelength-pdf", str(table))))
    for name in a.scenes or ():
        src = REPO / "scenes" / "benchmark" / name / "scene.pbrt"
        if not src.is_file():
            missing.append(f"no scene {src}")
            continue
        scene = edit_scene(src, None, tmp / f"{name}.pbrt", resolution=tuple(a.size))
        out += [(name, "own lamps", s, scene, flags) for s, flags in SCENE_SAMPLERS.items()]
    if missing:
        for m in missing:
            print(f"measure_wavelength_net: {m}", file=sys.stderr)
        sys.exit(2)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--benchmark", type=Path, help="a benchmark's output folder (its jobs and tables)")
    ap.add_argument("--only", nargs="+", default=None, metavar="PREFIX",
                    help="the benchmark's jobs whose name (SCENE/LAMP/PIXEL-SAMPLER) starts so")
    ap.add_argument("--rows", nargs="+", default=["spd", "optimized"], help="the lamp's tables (default spd optimized)")
    ap.add_argument("--scenes", nargs="+", default=None, help="the project's scenes with their own lamps")
    ap.add_argument("--size", type=int, nargs=2, default=(160, 120), help="their film size (default 160 120)")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--pairs", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pbrt", type=Path, default=REPO / "build" / "pbrt")
    ap.add_argument("--out", type=Path, help="the CSV to write")
    a = ap.parse_args()
    if a.benchmark is None and not a.scenes:
        ap.error("give --benchmark OUT or --scenes NAME ...")
    if a.spp < 1 or a.pairs < 1:
        ap.error("--spp and --pairs must be at least 1")
    if not a.pbrt.is_file():
        ap.error(f"no renderer at {a.pbrt} (bash scripts/setup.sh builds it)")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        todo = cases(a, tmp)
        for n, (case, kind, sampler, scene, flags) in enumerate(todo):
            print(f"[{n + 1}/{len(todo)}] {case} {sampler}", file=sys.stderr, flush=True)
            images = {False: [], True: []}
            cpu = {False: [], True: []}
            for seed in range(1, 2 * a.pairs + 1):
                for net in (False, True):
                    out = tmp / f"{n}-{int(net)}-{seed}.exr"
                    r = subprocess.run([str(a.pbrt), "--quiet", "--nthreads", str(a.threads), "--spp", str(a.spp),
                                        "--seed", str(seed), *flags, *(NET if net else ()), "--outfile", str(out),
                                        str(scene)], capture_output=True, text=True)
                    if r.returncode != 0:
                        sys.exit(f"measure_wavelength_net: {case} {sampler}: {r.stderr.strip()}")
                    images[net].append(read_rgb(out))
                    cpu[net].append(float(read_header(out)["renderCPUSeconds"]))
            mask = lit_pixels(np.mean(images[False] + images[True], axis=0))
            err = {}
            for net, ims in images.items():
                maps = [_delta_e(rgb_to_lab(ims[2 * i]), rgb_to_lab(ims[2 * i + 1]))[mask] for i in range(a.pairs)]
                err[net] = (float(np.mean([np.mean(m * m) / 2 for m in maps])),
                            float(np.mean([m.mean() for m in maps])) / np.sqrt(2), float(np.mean(cpu[net])))
            (d0, m0, t0), (d1, m1, t1) = err[False], err[True]
            rows.append({"case": case, "kind": kind, "sampler": sampler, "spp": a.spp, "pairs": a.pairs,
                         "de2": f"{d0:.5g}", "de2_net": f"{d1:.5g}", "de2_ratio": f"{d1 / d0:.4f}",
                         "de2_ratio_equal_time": f"{equal_time_ratio(d1, t1, d0, t0):.4f}",
                         "mean_de": f"{m0:.5g}", "mean_de_net": f"{m1:.5g}", "mean_de_ratio": f"{m1 / m0:.4f}",
                         "mean_de_ratio_equal_time": f"{equal_time_ratio(m1, t1, m0, t0, 0.5):.4f}",
                         "cpu": f"{t0:.4g}", "cpu_net": f"{t1:.4g}", "cpu_ratio": f"{t1 / t0:.4f}"})
            print(f"    de2 {d0:.4g} -> {d1:.4g} ({d1 / d0:.3f}), mean ΔE00 {m0:.4g} -> {m1:.4g} ({m1 / m0:.3f}), "
                  f"CPU {t0:.3g} -> {t1:.3g} s", file=sys.stderr, flush=True)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        with open(a.out, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    print("| kind | sampler | cases | de2 with / without the net, median (range) | mean ΔE00, median (range) | "
          "CPU, median |\n|---|---|---|---|---|---|")
    groups = sorted({(r["kind"], r["sampler"]) for r in rows})
    for kind, sampler in groups:
        g = [r for r in rows if r["kind"] == kind and r["sampler"] == sampler]
        d = [float(r["de2_ratio"]) for r in g]
        m = [float(r["mean_de_ratio"]) for r in g]
        c = [float(r["cpu_ratio"]) for r in g]
        print(f"| {kind} | {sampler} | {len(g)} | {np.median(d):.3f} ({min(d):.3f}-{max(d):.3f}) | "
              f"{np.median(m):.3f} ({min(m):.3f}-{max(m):.3f}) | {np.median(c):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
