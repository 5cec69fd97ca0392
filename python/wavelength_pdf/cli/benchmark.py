"""``wavelength-pdf benchmark``: every sampler side by side (design §6.7, docs/benchmark.md)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wavelength_pdf.cli import cluster_args
from wavelength_pdf.evaluation.benchmark import grid as G

SWEEPS = ("all", "lamps", "scenes", "small")


def cmd_benchmark(args) -> int:
    from wavelength_pdf.evaluation.benchmark import copy_report, run_benchmark
    from wavelength_pdf.renderer import find_pbrt

    if args.sweep == "small":
        spec = G.small_grid(args.shared)
    else:
        spec = G.full_grid(args.shared)
        if args.sweep != "all":
            spec = G.select(spec, [args.sweep])
    spec = G.select(spec, args.only)
    try:
        spec = G.with_rows(spec, args.rows)
    except ValueError as e:
        print(f"wavelength-pdf benchmark: --rows: {e}", file=sys.stderr)
        return 2
    spec = G.with_wavelength_net(spec, args.wavelength_net)
    find_pbrt(args.pbrt)  # exit 2 before any work when there is no renderer (design §7)
    if args.list:
        for j in spec.jobs:
            print(j.name)
        for s in spec.skipped:
            print(f"skipped: {s}", file=sys.stderr)
        return 0
    command = "wavelength-pdf benchmark" + ("" if args.sweep == "all" else f" --sweep {args.sweep}") + \
        (" --wavelength-net" if args.wavelength_net else "")
    run_benchmark(spec, args.outdir, workers=args.workers, scheduler=args.scheduler, nthreads=args.nthreads,
                  pbrt=args.pbrt, timing=args.timing, timing_rounds=args.timing_rounds,
                  timing_spp=args.timing_spp, command=command, render=not args.no_render)
    print(f"report: {args.outdir / 'report.md'}; results: {args.outdir / 'results.csv'}")
    if args.docs is not None:
        copied = copy_report(args.outdir, args.docs)
        print(f"copied {len(copied)} files to {args.docs}")
    return 0


def add_parser(sub, out: Path) -> None:
    b = sub.add_parser(
        "benchmark", help="every wavelength sampler side by side, as tables: error against spp and CPU time, "
                          "the floor, equal time (resumable; docs/benchmark.md)",
        description="Renders every job of the benchmark (design §6.7): the lamp sweep (every lamp on two "
                    "cheap scenes) and the scene sweep (every scene under a handful of lamps, with the "
                    "low-discrepancy and the independent pixel sampler). Every sampler is a table (uniform, "
                    "visible, spd, luminance, xyz, the optimizer's start, the optimized table, the table "
                    "optimized for a pixel (--objective stratified), the tables for the scene's own colours, "
                    "earlier work's tables), beside pbrt-v4's own visible sampling and a floor (--wavelength-repeats). "
                    "Errors come from independent seed pairs (no reference needed) and against a reference "
                    "drawn with other samplers. Finished renders are reused: an interrupted run resumes. "
                    "Scenes and LSPDD lamps come from --shared; jobs whose material is missing are skipped.")
    b.add_argument("--sweep", choices=SWEEPS, default="all",
                   help="which jobs: all (default), lamps, scenes, or small (tiny images of the project's own "
                        "box, as the test suite runs it)")
    b.add_argument("--only", nargs="+", default=None, metavar="PREFIX",
                   help="only the jobs whose name (SCENE/LAMP/PIXEL-SAMPLER, see --list) starts with one of these")
    b.add_argument("--rows", nargs="+", default=None, metavar="ROW",
                   help="render and score only these rows of each job (" + ", ".join(G.ROWS) + "); "
                        "the floor, the reference and pbrt-v4's own visible sampling are always rendered "
                        "(default: every row of the job)")
    b.add_argument("--wavelength-net", action="store_true",
                   help="render every image (rows, floor, reference) with pbrt --wavelength-net (design §5.2); "
                        "give it its own -o, since the renders differ")
    b.add_argument("--list", action="store_true", help="list the jobs and exit")
    b.add_argument("-o", "--outdir", type=Path, default=out / "benchmark", help="output folder (default out/benchmark)")
    b.add_argument("--shared", type=Path, default=G.SHARED,
                   help=f"the shared material: scenes/, spectra/lspdd/, tables/ (default {G.SHARED})")
    b.add_argument("--timing", action="store_true",
                   help="also measure CPU seconds per image, one render at a time on one thread, alternating "
                        "the samplers (run on an idle machine), for equal-time ratios")
    b.add_argument("--timing-rounds", type=int, default=5, metavar="R", help="renders per sampler (default 5)")
    b.add_argument("--timing-spp", type=int, default=64, metavar="N", help="spp of the timed renders (default 64)")
    b.add_argument("--no-render", action="store_true",
                   help="score and report the renders already there, render nothing (jobs not "
                        "finished are named and left out)")
    b.add_argument("--docs", type=Path, default=None, metavar="DIR",
                   help="also copy report.md, the CSVs and the plots to DIR (e.g. docs/benchmark)")
    b.add_argument("--nthreads", type=int, default=None, help="renderer threads per render (default: cores/workers)")
    b.add_argument("--pbrt", type=Path, default=None, help="the renderer (default: as design §7)")
    cluster_args(b)
    b.set_defaults(func=cmd_benchmark, extra="evaluation")
