"""Several tables on one scene against one ground truth: mean CIEDE2000 and time per spp.

For the whole-scene and reflectance-aware modes (design §3.1, §4.5, §6.1a): the scene is
either lit by one spectrum (``--spectrum SPECTRUM``, as ``evaluate`` lights it) or keeps its own
emitters (``--spectrum whole-scene``); every table given as ``NAME=TABLE.csv`` is rendered
with the same seeds beside stratified uniform sampling, and every image is scored per pixel
against one truth rendered with stratified uniform sampling (the unbiased baseline, so no
table is favoured). Prints a Markdown table (mean ΔE, the spread over seeds, render seconds)
and, for the highest spp, each table's relative difference of the image mean from the
truth's (unbiasedness), and writes results.csv and a plot to OUTDIR.

    python scripts/bench_scene_tables.py scenes/cornell-box-two-lamps/scene.pbrt \\
        --spectrum whole-scene --tables whole=whole.csv fl=fl.csv hps=hps.csv -o out/bench
"""
from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

from wavelength_pdf.evaluation import metrics, render as rendering
from wavelength_pdf.evaluation.protocol import WHOLE_SCENE, RenderJob
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.exr import read_rgb
from wavelength_pdf.renderer import find_pbrt
from wavelength_pdf.spectra import load_spectrum
from wavelength_pdf.table import read_table


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", type=Path)
    ap.add_argument("--spectrum", required=True, help=f"a spectrum, or '{WHOLE_SCENE}'")
    ap.add_argument("--tables", nargs="+", required=True, metavar="NAME=TABLE")
    ap.add_argument("-o", "--outdir", type=Path, required=True)
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 64, 512])
    ap.add_argument("--truth-spp", type=int, default=8192)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--resolution", default="64x64")
    ap.add_argument("--nthreads", type=int, default=None)
    ap.add_argument("--pbrt", type=Path, default=None)
    args = ap.parse_args(argv)

    lo, hi = 380.0, 780.0
    w, h = (int(v) for v in args.resolution.lower().split("x"))
    pbrt = find_pbrt(args.pbrt)
    tables = {}
    for item in args.tables:
        name, _, path = item.partition("=")
        read_table(path)  # a bad table stops here, before any render
        tables[name] = rendering.Sampler(name, f"table {name}", ("--wavelength-pdf", str(Path(path).resolve())))
    uniform = rendering.samplers(None, lo, hi)["uniform"]
    keep = args.spectrum == WHOLE_SCENE
    spectrum = None if keep else load_spectrum(args.spectrum, lo=lo, hi=hi)
    args.outdir.mkdir(parents=True, exist_ok=True)
    scene = edit_scene(args.scene, spectrum, args.outdir / "scene.pbrt", lo=lo, hi=hi, resolution=(w, h))
    renders = args.outdir / "renders"

    truth_job = RenderJob(scene, renders / f"truth-uniform-{args.truth_spp}.exr", uniform, args.truth_spp,
                          10_000, pbrt)
    print(f"truth: uniform, {args.truth_spp} spp, {w}x{h}", file=sys.stderr)
    truth = read_rgb(truth_job.run(args.nthreads).image)
    methods = {"uniform": uniform, **tables}
    rows = []
    finest = {}
    for spp in args.spp:
        for name, sampler in methods.items():
            means, secs = [], []
            for seed in range(1, args.seeds + 1):
                job = RenderJob(scene, renders / f"{name}-{spp}-seed{seed}.exr", sampler, spp, seed, pbrt)
                r = job.run(args.nthreads)
                img = read_rgb(r.image)
                means.append(metrics.ErrorStats.of(metrics.delta_e_map(img, truth)).mean)
                secs.append(r.seconds)
                if spp == max(args.spp):
                    finest.setdefault(name, []).append(img)
            rows.append({"method": name, "spp": spp, "mean": float(np.mean(means)),
                         "sd": float(np.std(means, ddof=1)) if len(means) > 1 else float("nan"),
                         "seconds": float(np.mean(secs)), "seeds": len(means)})
            print(f"{name} {spp} spp: mean dE {rows[-1]['mean']:.4f}", file=sys.stderr)
    with open(args.outdir / "results.csv", "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)

    print(f"| method | spp | mean ΔE00 | sd over {args.seeds} seeds | seconds |")
    print("|---|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['method']} | {r['spp']} | {r['mean']:.4f} | {r['sd']:.4f} | {r['seconds']:.2f} |")
    print()
    t_mean = truth.reshape(-1, truth.shape[-1])[:, :3].mean(axis=0)
    print(f"image mean against the truth at {max(args.spp)} spp (relative, R G B), "
          f"all {args.seeds} seeds averaged:")
    for name, imgs in finest.items():
        m = np.mean([im.reshape(-1, im.shape[-1])[:, :3].mean(axis=0) for im in imgs], axis=0)
        print(f"- {name}: " + " ".join(f"{v:+.2e}" for v in (m - t_mean) / t_mean))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.5))
    for name in methods:
        rs = [r for r in rows if r["method"] == name]
        ax.errorbar([r["spp"] for r in rs], [r["mean"] for r in rs],
                    yerr=[0 if np.isnan(r["sd"]) else r["sd"] for r in rs], marker="o", label=name, capsize=3)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("samples per pixel")
    ax.set_ylabel("mean CIEDE2000")
    ax.set_title(f"{args.scene.parent.name}: {args.spectrum}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.outdir / "error-vs-spp.png", dpi=120)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
