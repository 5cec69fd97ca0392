"""The evaluation's subcommands of ``wavelength-pdf``: ``evaluate``, ``grid`` and ``demo``.

``demo`` is the README's main job: the project's own Cornell box (``scenes/cornell-box``) lit
by the project's tri-band fluorescent spectrum, at a resolution and spp that fit a small
machine, with the table optimized on the way; it prints the results table.
"""
from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

from tqdm import tqdm

from wavelength_pdf.evaluation import report
from wavelength_pdf.evaluation.protocol import DEFAULT_METHODS, DEFAULT_SPP, Config, evaluate, write_rows
from wavelength_pdf.evaluation.render import DEFAULT_PBRT, REPO
from wavelength_pdf.spectra import load_spectrum

DEMO_SCENE = REPO / "scenes" / "cornell-box" / "scene.pbrt"
DEMO_SPECTRUM = REPO / "spectra" / "tri-band-fluorescent.spd"


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(f"resolution must be positive, got {text!r}")
    return w, h


def _common(p: argparse.ArgumentParser, spp=DEFAULT_SPP, truth_spp=8192, resolution="128x128") -> None:
    p.add_argument("--spp", type=int, nargs="+", default=list(spp),
                   help=f"samples per pixel of the compared images (default: {' '.join(map(str, spp))})")
    p.add_argument("--methods", nargs="+", default=list(DEFAULT_METHODS), choices=list(DEFAULT_METHODS),
                   help="wavelength samplers to compare: uniform = stratified uniform over the table's "
                        "range (the baseline), visible = pbrt-v4's default, table = the optimized table")
    p.add_argument("--truth-spp", type=int, default=truth_spp,
                   help=f"samples per pixel of the ground truth (default {truth_spp}; cached)")
    p.add_argument("--truth-method", default="uniform", choices=list(DEFAULT_METHODS),
                   help="sampler of the ground truth (default uniform; any unbiased one converges)")
    p.add_argument("--resolution", type=_resolution, default=_resolution(resolution),
                   help=f"image size WxH, overriding the scene's film (default {resolution})")
    p.add_argument("--range", type=float, nargs=2, default=(380.0, 780.0), metavar=("LO", "HI"),
                   help="wavelength range of the table and of every sampler, nm (default 380 780)")
    p.add_argument("--seed", type=int, default=1, help="renderer seed of the compared images")
    p.add_argument("--nthreads", type=int, default=None, help="renderer threads (default: all cores)")
    p.add_argument("--pbrt", type=Path, default=DEFAULT_PBRT, help=f"renderer binary (default {DEFAULT_PBRT})")


def add_subcommands(sub) -> None:
    """Register ``evaluate``, ``grid`` and ``demo`` on the main parser's subparsers."""
    p = sub.add_parser("evaluate", help="render ground truth, baseline and table images of a scene lit "
                                        "by a spectrum; report CIEDE2000 against spp and time",
                       description="Renders a copy of SCENE lit by SPECTRUM with each sampler at each spp, "
                                   "compares every image per pixel with a high-spp ground truth in "
                                   "CIEDE2000 and writes results.csv, results.md and plots to OUTDIR.")
    p.add_argument("scene", type=Path, help="a pbrt-v4 scene")
    p.add_argument("spectrum", help="the lamp spectrum (any input the optimizer reads, e.g. cie:FL11)")
    p.add_argument("-o", "--outdir", type=Path, required=True, help="output folder (renders are cached there)")
    p.add_argument("--table", type=Path, default=None, help="use this table instead of optimizing one")
    _common(p)
    p.set_defaults(func=cmd_evaluate)

    g = sub.add_parser("grid", help="many scene x spectrum evaluations with one progress bar (resumable)",
                       description="Runs `evaluate` for every SCENE x SPECTRUM pair into OUTDIR/<scene>/<spectrum>/, "
                                   "reusing finished renders, and writes one combined results table.")
    g.add_argument("--scenes", type=Path, nargs="+", required=True, help="pbrt-v4 scenes")
    g.add_argument("--spectra", nargs="+", required=True, help="lamp spectra")
    g.add_argument("-o", "--outdir", type=Path, required=True, help="output folder")
    _common(g)
    g.set_defaults(func=cmd_grid)

    d = sub.add_parser("demo", help="the main job: the project's Cornell box under its tri-band lamp "
                                    "(no ../shared needed)",
                       description="Optimizes a table for spectra/tri-band-fluorescent.spd, renders "
                                   "scenes/cornell-box with each sampler and prints the comparison.")
    d.add_argument("-o", "--outdir", type=Path, default=REPO / "out" / "demo", help="output folder (default out/demo)")
    d.add_argument("--scene", type=Path, default=DEMO_SCENE, help="scene (default: the project's Cornell box)")
    d.add_argument("--spectrum", default=str(DEMO_SPECTRUM), help="spectrum (default: the tri-band lamp)")
    d.add_argument("--table", type=Path, default=None, help="use this table instead of optimizing one")
    _common(d, spp=(16, 64, 256), truth_spp=4096, resolution="96x96")
    d.set_defaults(func=cmd_demo)


def _config(args) -> Config:
    return Config(spp=args.spp, methods=args.methods, truth_spp=args.truth_spp, truth_method=args.truth_method,
                  resolution=args.resolution, seed=args.seed, nthreads=args.nthreads,
                  lo=args.range[0], hi=args.range[1], pbrt=args.pbrt)


def run_one(scene: Path, spectrum_spec: str, outdir: Path, config: Config, table: Path | None,
            bar: tqdm | None = None):
    spectrum = load_spectrum(spectrum_spec, lo=config.lo, hi=config.hi)

    def say(msg: str) -> None:
        if bar is not None:
            bar.set_postfix_str(msg)
            if msg.startswith(tuple(config.methods)):
                bar.update(1)

    ev = evaluate(scene, spectrum, outdir, config, table=table, progress=say)
    title = f"{ev.rows[0].scene} under {spectrum.name}"
    report.plot_error(ev.rows, outdir / "error-vs-spp-and-time.png", title)
    report.plot_error_maps(ev.error_maps, outdir / "error-maps.png", title)
    (outdir / "results.md").write_text(report.markdown_table(ev.rows))
    return ev


def cmd_evaluate(args) -> int:
    config = _config(args)
    with tqdm(total=len(config.methods) * len(config.spp), desc="evaluate", file=sys.stderr, unit="image") as bar:
        ev = run_one(args.scene, args.spectrum, args.outdir, config, args.table, bar)
    print(report.markdown_table(ev.rows))
    print(f"results: {args.outdir / 'results.csv'}; plots: {args.outdir}/*.png")
    return 0


def cmd_grid(args) -> int:
    config = _config(args)
    jobs = list(itertools.product(args.scenes, args.spectra))
    rows = []
    with tqdm(total=len(jobs) * len(config.methods) * len(config.spp), desc="grid", file=sys.stderr,
              unit="image") as bar:
        for scene, spec in jobs:
            sub = args.outdir / (scene.parent.name or scene.stem) / Path(spec.replace(":", "-")).stem
            rows += run_one(scene, spec, sub, config, None, bar).rows
    write_rows(args.outdir / "results.csv", rows)
    (args.outdir / "results.md").write_text(report.markdown_table(rows))
    print(report.markdown_table(rows))
    return 0


def cmd_demo(args) -> int:
    config = _config(args)
    print(f"demo: {args.scene.relative_to(REPO) if args.scene.is_relative_to(REPO) else args.scene} "
          f"lit by {args.spectrum}; output in {args.outdir}", file=sys.stderr)
    with tqdm(total=len(config.methods) * len(config.spp), desc="demo", file=sys.stderr, unit="image") as bar:
        ev = run_one(args.scene, args.spectrum, args.outdir, config, args.table, bar)
    print(report.markdown_table(ev.rows))
    print(f"table: {ev.table}\nresults: {args.outdir / 'results.csv'}\n"
          f"plots: {args.outdir / 'error-vs-spp-and-time.png'}, {args.outdir / 'error-maps.png'}")
    return 0
