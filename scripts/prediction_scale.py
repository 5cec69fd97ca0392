#!/usr/bin/env python3
"""Is the image's prediction right in scale? Job by job over a finished lamp-sweep benchmark,
each row's measured wavelength noise (its `de2` less the job's measured floor) over its predicted
wavelength error (`wavelength-pdf choose`'s prediction, `evaluation.choose.rank`, with each
pixel's spread, design §6.8), per scene, spp and row (docs/benchmark.md, "A pixel's spread path
by path").

A ratio of 1 is a prediction right in scale; the spread of the ratios over the jobs says how
far one job's figure can be trusted. Rows whose noise is within the floor's own noise give
ratios near 0 or below; the medians are what is meant.

    .venv/bin/python scripts/prediction_scale.py -o out/benchmark-net --csv scale.csv
"""
from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python"))

#: The rows predicted: the simple samplers, J's table and the image's own.
ROWS = ("uniform", "visible", "spd", "luminance", "xyz", "optimized", "optimized-image")


def main(argv=None) -> int:
    import numpy as np

    from wavelength_pdf import aot, progress
    from wavelength_pdf.evaluation import choose
    from wavelength_pdf.evaluation.benchmark import grid as G
    from wavelength_pdf.evaluation.benchmark.predict import read_results, scene_transfer
    from wavelength_pdf.spectra import load_spectrum
    from wavelength_pdf.table import read_table

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("-o", "--outdir", type=Path, default=HERE.parent / "out" / "benchmark",
                    help="the benchmark's output folder, with results.csv, tables/, jobs/ and transfer/ "
                         "(default out/benchmark)")
    ap.add_argument("--shared", type=Path, default=G.SHARED, help=f"the shared material (default {G.SHARED})")
    ap.add_argument("--scenes", nargs="+", default=None, help="scenes (default: every lamp-sweep scene in the results)")
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 64], help="sample counts (default 16 64)")
    ap.add_argument("--pbrt", type=Path, default=None, help="the renderer (default: as design §7)")
    ap.add_argument("--net", action="store_true",
                    help="the benchmark was rendered with --wavelength-net: the spread between a pixel's cells "
                         "counts as stratified (design §6.8)")
    ap.add_argument("--csv", type=Path, default=None, help="write every job's figures here")
    a = ap.parse_args(argv)

    results = a.outdir / "results.csv"
    problems = [p for p, bad in ((f"no results file {results}", not results.is_file()),
                                 (f"no shared material at {a.shared} (--shared)", not a.shared.is_dir()))
                if bad]
    if problems:
        for p in problems:
            print(f"prediction_scale: {p}", file=sys.stderr)
        return 2
    measured: dict[tuple[str, str, int], dict[str, float]] = {}
    for r in read_results(results):
        if "lamps" in r["sweep"].split("+") and r["pixel_sampler"] == "sobol" and r["lamp"] != "own":
            measured.setdefault((r["scene"], r["lamp"], r["spp"]), {})[r["row"]] = r["de2"]
    scenes = a.scenes or sorted({k[0] for k in measured})
    jobs = sorted({(s, lamp) for s, lamp, spp in measured if s in scenes and spp in a.spp})
    if not jobs:
        print(f"prediction_scale: no lamp-sweep job of {', '.join(scenes)} at {a.spp} spp in {results}",
              file=sys.stderr)
        return 2
    lines = []
    transfers = {}  # loading one is seconds (its spread): once per scene
    with progress.bar(total=len(jobs), desc="prediction scale", unit="job", file=sys.stderr) as bar:
        for scene, lamp in jobs:
            if scene not in transfers:
                transfers[scene] = scene_transfer(scene, a.outdir, a.shared, a.pbrt, spread=True, net=a.net)
            tr = transfers[scene]
            spectrum = load_spectrum(G.LAMPS[lamp].spec(a.shared), lo=380.0, hi=780.0)
            folder = a.outdir / "jobs" / scene / lamp / "sobol"
            for spp in a.spp:
                m = measured.get((scene, lamp, spp), {})
                if G.FLOOR not in m:
                    continue  # no floor measured at this spp: nothing to subtract
                cands = choose.simple_tables(spectrum)
                optimized = a.outdir / "tables" / lamp / "optimized.csv"
                image = folder / G.image_table_name(spp)
                for name, path in (("optimized", optimized), (G.IMAGE, image)):
                    if path.is_file():
                        cands[name] = read_table(path)
                for p in choose.rank(spectrum, tr, cands, spp):
                    if p.name in m:
                        lines.append({"scene": scene, "lamp": lamp, "spp": spp, "row": p.name,
                                      "de2": m[p.name], "floor": m[G.FLOOR], "predicted": p.wavelength,
                                      "ratio": (m[p.name] - m[G.FLOOR]) / p.wavelength})
                aot.clear_memory()  # each lamp compiles for its own shapes
            bar.update(1)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(lines[0]))
            w.writeheader()
            w.writerows({k: (f"{v:.5g}" if isinstance(v, float) else v) for k, v in ln.items()} for ln in lines)
    rows = [r for r in ROWS if any(ln["row"] == r for ln in lines)]
    print("| scene | spp | jobs | " + " | ".join(rows) + " |")
    print("|---|---|---|" + "---|" * len(rows))
    for scene in scenes:
        for spp in a.spp:
            cells = []
            for row in rows:
                v = np.array([ln["ratio"] for ln in lines if (ln["scene"], ln["spp"], ln["row"]) == (scene, spp, row)])
                cells.append(f"{np.median(v):.2f} ({np.percentile(v, 25):.2f}-{np.percentile(v, 75):.2f})"
                             if v.size else "–")
            n = len({ln["lamp"] for ln in lines if (ln["scene"], ln["spp"]) == (scene, spp)})
            print(f"| {scene} | {spp} | {n} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
