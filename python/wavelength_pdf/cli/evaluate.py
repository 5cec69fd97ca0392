"""The evaluation's subcommands of ``wavelength-pdf``: ``evaluate``, ``grid``, ``published``, ``demo``
(the renderers they run: :mod:`wavelength_pdf.evaluation.backends`).

``demo`` is the README's main job: the project's own Cornell box (``scenes/cornell-box``) lit
by the project's tri-band fluorescent spectrum, at a resolution and spp that fit a small
machine, with the table optimized on the way; it prints the results table.
"""
from __future__ import annotations

import argparse
import itertools
import shutil
import sys
import time
from pathlib import Path
from typing import Sequence

from wavelength_pdf import data, progress
from wavelength_pdf.cli import cluster_args, out_folder
from wavelength_pdf.evaluation.backends import BACKENDS, backend
from wavelength_pdf.evaluation.protocol import (DEFAULT_METHODS, DEFAULT_SPP, Config, check_config,
                                                finish, plan, write_rows, WHOLE_SCENE)
from wavelength_pdf.evaluation.render import REPO
from wavelength_pdf.renderer import PBRT_ENV, find_pbrt
from wavelength_pdf.produce import safe_name
from wavelength_pdf.spectra import load_spectrum
from wavelength_pdf.table import read_table

DEMO_SCENE = data.demo_scene()
DEMO_SPECTRUM = data.demo_spectrum()
#: Default output folders: under the checkout, or the current folder when installed.
OUT = out_folder()


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(f"resolution must be positive, got {text!r}")
    return w, h


def _scale(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"the scale must be positive, got {text!r}")
    return v


def _common(p: argparse.ArgumentParser, spp=DEFAULT_SPP, truth_spp=8192, resolution: str | None = "128x128",
            scale: float | None = None, truth_method="table", seeds=1) -> None:
    p.add_argument("--spp", type=int, nargs="+", default=list(spp),
                   help=f"samples per pixel of the compared images (default: {' '.join(map(str, spp))})")
    p.add_argument("--methods", nargs="+", default=list(DEFAULT_METHODS), choices=list(DEFAULT_METHODS),
                   help="wavelength samplers to compare: uniform = stratified uniform over the table's "
                        "range (the baseline), visible = pbrt-v4's default, table = the optimized table")
    p.add_argument("--truth-spp", type=int, default=truth_spp,
                   help=f"samples per pixel of the ground truth (default {truth_spp}; cached)")
    p.add_argument("--truth-method", default=truth_method, choices=list(DEFAULT_METHODS),
                   help=f"sampler of the ground truth (default {truth_method}; every one is unbiased, the "
                        "table converges fastest on line spectra)")
    p.add_argument("--seeds", type=int, default=seeds,
                   help=f"images per method and spp, with seeds SEED, SEED+1, ...; their spread is the noise "
                        f"of the mean error (default {seeds})")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--resolution", type=_resolution, default=None,
                      help=f"image size WxH, overriding the scene's film (default {resolution or 'the scene'})")
    size.add_argument("--resolution-scale", type=_scale, default=None, metavar="S",
                      help="scale the scene's own film size by S instead (e.g. 0.125 = 1/8 a side)"
                           + (f" (default {scale:g})" if scale else ""))
    p.set_defaults(default_resolution=_resolution(resolution) if resolution else scale)
    p.add_argument("--range", type=float, nargs=2, default=(380.0, 780.0), metavar=("LO", "HI"),
                   help="wavelength range of the table and of every sampler, nm (default 380 780)")
    p.add_argument("--truth-chunks", type=int, default=1, metavar="K",
                   help="render the ground truth as K independent images (seeds of their own, TRUTH_SPP/K spp "
                        "each) that run in parallel and are merged weighted by spp (default 1)")
    p.add_argument("--seed", type=int, default=1, help="renderer seed of the compared images")
    p.add_argument("--nthreads", type=int, default=None, help="renderer threads (default: all cores)")
    p.add_argument("--pbrt", type=Path, default=None,
                   help=f"renderer binary (default: ${PBRT_ENV}, else the checkout's build/pbrt, "
                        "else the wheel's own, else pbrt on PATH)")
    p.add_argument("--reflectances", default=None, metavar="SET",
                   help="optimize the tables for coloured surfaces (design §4.5): 'scene' (the "
                        "scene's materials), 'colorchecker' or a reflectance CSV (design §3.4)")


def _renderer(p: argparse.ArgumentParser) -> None:
    p.add_argument("--renderer", choices=tuple(BACKENDS), default="pbrt",
                   help="pbrt (build/pbrt, a .pbrt scene) or mitsuba (Mitsuba 3, llvm_ad_spectral, a .xml "
                        "scene such as scenes/cornell-box/scene.xml; visible = Mitsuba's default; "
                        "needs no pbrt)")


def add_subcommands(sub) -> None:
    """Register ``evaluate``, ``grid``, ``published`` and ``demo`` on the main parser's subparsers."""
    p = sub.add_parser("evaluate", help="render ground truth, baseline and table images of a scene lit "
                                        "by a spectrum; report CIEDE2000 against spp and time",
                       description="Renders a copy of SCENE lit by SPECTRUM with each sampler at each spp, "
                                   "compares every image per pixel with a high-spp ground truth in "
                                   "CIEDE2000 and writes results.csv, results.md and plots to OUTDIR.")
    p.add_argument("scene", type=Path, help="a pbrt-v4 scene")
    p.add_argument("spectrum", help="the lamp spectrum (any input the optimizer reads, e.g. cie:FL11); "
                                    f"'{WHOLE_SCENE}': the scene keeps its own emitters and the table is "
                                    "optimized for their total emission (optimize --whole-scene)")
    p.add_argument("-o", "--outdir", type=Path, required=True, help="output folder (renders are cached there)")
    p.add_argument("--table", type=Path, default=None, help="use this table instead of optimizing one")
    _common(p)
    _renderer(p)
    p.set_defaults(func=cmd_evaluate, extra="evaluation")

    g = sub.add_parser("grid", help="many scene x spectrum evaluations with one progress bar (resumable)",
                       description="Runs `evaluate` for every SCENE x SPECTRUM pair (or for the given "
                                   "--pairs) into OUTDIR/<scene>/<spectrum>/, reusing finished renders, and "
                                   "writes one combined results table, report.md and summary plots.")
    g.add_argument("--scenes", type=Path, nargs="+", default=[], help="pbrt-v4 scenes")
    g.add_argument("--spectra", nargs="+", default=[], help="lamp spectra (every scene gets every spectrum)")
    g.add_argument("--pairs", nargs="+", default=[], metavar="SCENE=SPECTRUM",
                   help="scene and spectrum pairs, instead of (or besides) the full --scenes x --spectra grid")
    g.add_argument("-o", "--outdir", type=Path, required=True, help="output folder")
    _common(g)
    cluster_args(g)
    g.set_defaults(func=cmd_grid, extra="evaluation")

    pub = sub.add_parser("published", help="the published comparison (six scenes; LSPDD lamps, CIE D65 and A), "
                                           "at reduced resolution, from ../shared",
                         description="Runs the grid of the published evaluation, every row of its table: the "
                                     "Cornell box under the compact fluorescent (LSPDD 2482), the sun (2629) and "
                                     "the scotopic curve (2639); the teapot (2482, 2629); Veach bidir (2482); "
                                     "Veach MIS under CIE A (2659), the Philips High Bay metal halide (2641) and "
                                     "the sun; the staircase (D65, 2641); the glass of water (D65, A, 2482). The "
                                     "report shows the published ratio beside the measured one. Scenes and "
                                     "spectra come from --shared.")
    pub.add_argument("--shared", type=Path, default=default_shared(),
                     help="folder with scenes/ and spectra/lspdd/ (default: ../shared beside the "
                          "repository in a checkout; ./shared when the package is installed)")
    pub.add_argument("-o", "--outdir", type=Path, default=OUT / "published",
                     help="output folder (default out/published)")
    pub.add_argument("--only", nargs="+", default=None, metavar="SCENE/SPECTRUM",
                     help="run only these jobs, e.g. cornell-box/2482")
    pub.add_argument("--docs", type=Path, default=None, metavar="DIR",
                     help="also copy report.md, results.csv and every plot (not the renders) to DIR, "
                          "e.g. docs/evaluation")
    _common(pub, spp=(16, 64, 256, 512), truth_spp=16384, resolution=None, scale=0.125,
            seeds=3)
    cluster_args(pub)
    pub.set_defaults(func=cmd_published, extra="evaluation")

    d = sub.add_parser("demo", help="the main job: the project's Cornell box under its tri-band lamp "
                                    "(no ../shared needed)",
                       description="Optimizes a table for spectra/tri-band-fluorescent.spd, renders "
                                   "scenes/cornell-box with each sampler and prints the comparison.")
    d.add_argument("-o", "--outdir", type=Path, default=OUT / "demo", help="output folder (default out/demo)")
    d.add_argument("--scene", type=Path, default=DEMO_SCENE, help="scene (default: the project's Cornell box)")
    d.add_argument("--spectrum", default=str(DEMO_SPECTRUM), help="spectrum (default: the tri-band lamp)")
    d.add_argument("--table", type=Path, default=None, help="use this table instead of optimizing one")
    _common(d, spp=(16, 64, 256), truth_spp=4096, resolution="96x96")
    _renderer(d)
    d.set_defaults(func=cmd_demo, extra="evaluation")


#: The published comparison (Dobos 2025, its table of results): (scene folder, LSPDD number or
#: built-in name, label, the published baseline/table ratio of mean CIEDE2000; "" where the
#: publication gives none for the row).
PUBLISHED = (
    ("cornell-box", "2482", "compact fluorescent", "2.6"),
    ("cornell-box", "2629", "sun", "1.0-1.2"),
    ("cornell-box", "2639", "scotopic", "1.0-1.2"),
    ("teapot", "2482", "compact fluorescent", "2.9"),
    ("teapot", "2629", "sun", "1.0-1.2"),
    ("veach-bidir", "2482", "compact fluorescent", "3.5"),
    ("veach-mis", "2659", "CIE A", "1.0-1.2"),
    ("veach-mis", "2641", "Philips High Bay", "2.4"),
    ("veach-mis", "2629", "sun", "1.0-1.2"),
    ("staircase", "cie:D65", "CIE D65", "1.0-1.2"),
    ("staircase", "2641", "Philips High Bay", "2.0"),
    ("glass-of-water", "cie:D65", "CIE D65", "0.93"),
    ("glass-of-water", "cie:A", "CIE A", "1.0-1.2"),
    ("glass-of-water", "2482", "compact fluorescent", ""),
)


def _config(args) -> Config:
    resolution = args.resolution or args.resolution_scale or args.default_resolution
    b = backend(getattr(args, "renderer", "pbrt"))
    if not b.uses_pbrt:
        # Users of another renderer need no pbrt (design §6.4): nothing looks for it.
        if args.pbrt is not None:
            raise ValueError(f"--pbrt is not used with --renderer {b.name}")
        pbrt = None
    else:
        pbrt = find_pbrt(args.pbrt)
    if not b.scene_queries and args.reflectances is not None:
        raise ValueError("--reflectances needs the pbrt renderer (the scene's materials come "
                         f"from pbrt); with --renderer {b.name}, leave it out")
    config = Config(spp=args.spp, methods=args.methods, truth_spp=args.truth_spp,
                    truth_method=args.truth_method, truth_chunks=args.truth_chunks, resolution=resolution,
                    seed=args.seed, seeds=args.seeds, nthreads=args.nthreads,
                    lo=args.range[0], hi=args.range[1], pbrt=pbrt,
                    reflectances=args.reflectances)
    check_config(config)
    if getattr(args, "workers", None) is not None and args.workers < 1:
        raise ValueError(f"--workers must be at least 1, got {args.workers}")
    return config


def _images(config: Config) -> int:
    return len(config.methods) * len(config.spp) * config.seeds


def job_outputs(ev, spectrum, outdir: Path) -> None:
    """A finished evaluation's plots: error against spp and time, error maps, colour bar,
    densities, and its results.md."""
    from wavelength_pdf import plots  # matplotlib: imported when a plot is drawn
    from wavelength_pdf.evaluation import report
    title = f"{ev.rows[0].scene} under {spectrum.name}"
    report.plot_error(ev.rows, outdir / "error-vs-spp-and-time.png", title)
    report.plot_error_maps(ev.error_maps, outdir / "error-maps.png", title)
    if Path(ev.table).is_file():  # a grid without table renders optimizes no table
        t = read_table(ev.table)
        plots.colour_bar_png(outdir / "colour-bar.png", spectrum, t)
        plots.densities_png(outdir / "densities.png", spectrum, t)
    (outdir / "results.md").write_text(report.markdown_table(ev.rows))


def run_one(scene: Path, spectrum_spec: str, outdir: Path, config: Config, table: Path | None,
            bar=None, renderer: str = "pbrt"):
    """One evaluation with its plots: error against spp and time, error maps, colour bar."""
    whole = spectrum_spec == WHOLE_SCENE
    b = backend(renderer)
    if not b.scene_queries and (whole or config.reflectances is not None):
        raise ValueError(f"'{WHOLE_SCENE}' and --reflectances need the pbrt renderer")
    spectrum, reflectances = job_inputs(scene, spectrum_spec, config)

    def say(msg: str) -> None:
        if bar is not None:
            bar.set_postfix_str(f"{outdir.name}: {msg}")
            if msg.startswith(tuple(config.methods)):
                bar.update(1)

    from wavelength_pdf.optimize import evaluation_budget

    total = evaluation_budget()
    shown = [0.0]
    # The table's optimization, shown on the same bar: twice a second on a terminal, a
    # plain line every 30 s elsewhere.
    every = 0.5 if sys.stderr.isatty() else 30.0

    def optimizing(step: int, J: float) -> None:
        now = time.monotonic()
        if bar is not None and (now - shown[0] > every or step >= total):
            shown[0] = now
            bar.set_postfix_str(f"{outdir.name}: optimizing the table, {min(step, total)}/{total} "
                                f"evaluations, J {J:.4g}", refresh=True)

    if bar is not None and table is None:  # the table's optimization starts by compiling
        bar.set_postfix_str(f"{outdir.name}: optimizing the table: {progress.preparing_message()}",
                            refresh=True)
    ev = b.evaluate(scene, spectrum, outdir, config, table=table, progress=say,
                    optimizer_progress=optimizing, keep_emitters=whole, reflectances=reflectances)
    say("plots")
    job_outputs(ev, spectrum, outdir)
    return ev


def cmd_evaluate(args) -> int:
    from wavelength_pdf.evaluation import report
    config = _config(args)
    with progress.bar(total=_images(config), desc="evaluate", file=sys.stderr, unit="image") as bar:
        ev = run_one(args.scene, args.spectrum, args.outdir, config, args.table, bar, args.renderer)
    print(report.markdown_table(ev.rows))
    print(f"results: {args.outdir / 'results.csv'}; plots: {args.outdir}/*.png")
    return 0


def _job_dir(outdir: Path, scene: Path, spectrum: str) -> Path:
    return outdir / (scene.parent.name or scene.stem) / safe_name(Path(spectrum.replace(":", "-")).stem)


def run_grid(jobs: list[tuple[Path, str]], outdir: Path, config: Config, title: str, *,
             workers: int | None = None, scheduler: str | None = None,
             tables: dict[int, Path] | None = None, published: Sequence[str] | None = None) -> list:
    """Evaluate every (scene, spectrum) job into its own folder, the renders on a Dask cluster
    (:mod:`.cluster`: a local one of ``workers`` processes, or the one at ``scheduler``); write
    the combined report. ``tables[i]``: a ready table for job i instead of optimizing one;
    ``published[i]``: job i's published ratio, shown beside the measured one."""
    from wavelength_pdf.evaluation import cluster, report

    for scene, _ in jobs:
        if not Path(scene).is_file():
            raise FileNotFoundError(2, "no such scene file", str(scene))
    # Everything that can be wrong with the inputs is found here, before any render.
    inputs = [job_inputs(Path(scene), spec, config) for scene, spec in jobs]
    spectra = [sp for sp, _ in inputs]
    # One table per spectrum: the first job's folder holds it, later jobs lit by the same
    # spectrum render with that one.
    needs_table = "table" in config.methods or config.truth_method == "table"
    chosen: list[Path] = []
    optimize: dict[Path, object] = {}
    first: dict[str, Path] = {}
    for i, ((scene, spec), sp) in enumerate(zip(jobs, spectra)):
        if (tables or {}).get(i) is not None:
            read_table(tables[i])
            chosen.append(Path(tables[i]))
            continue
        # The whole-scene spectrum is each scene's own.
        per_scene = spec == WHOLE_SCENE or config.reflectances == "scene"
        key = f"{Path(scene).resolve()}#{spec}" if per_scene else spec
        if key not in first:
            first[key] = _job_dir(outdir, Path(scene), spec) / "table.csv"
            if needs_table:
                optimize[first[key]] = (sp, inputs[i][1])
        chosen.append(first[key])
    plans = [plan(Path(scene), sp, _job_dir(outdir, Path(scene), spec), config, table=t,
                  keep_emitters=spec == WHOLE_SCENE)
             for (scene, spec), sp, t in zip(jobs, spectra, chosen)]
    with cluster.connect(workers, scheduler) as client:
        results = cluster.run(client, plans, optimize, config.nthreads, "grid")
    done = []
    for p, sp, (truth, images) in zip(plans, spectra, results):
        ev = finish(p, truth, images)
        job_outputs(ev, sp, p.outdir)
        done.append((p.outdir, ev.rows))
    rows = [r for _, job in done for r in job]
    write_rows(outdir / "results.csv", rows)
    marks = {(d[1][0].scene, d[1][0].illuminant): m for d, m in zip(done, published)} if published else None
    (outdir / "results.md").write_text(report.markdown_table(rows, published=marks))
    report.plot_summary(rows, outdir / "summary.png", title)
    report.write_report(outdir / "report.md", title, done, config, published=marks)
    return rows


def job_inputs(scene: Path, spectrum_spec: str, config: Config):
    """The spectrum (``whole-scene``: the scene's total emission, from the renderer) and the
    reflectance set (or None) of one evaluation job; bad input is found here."""
    if spectrum_spec == WHOLE_SCENE:
        from wavelength_pdf.scene_spectra import whole_scene_spectrum

        spectrum = whole_scene_spectrum(scene, lo=config.lo, hi=config.hi, pbrt=config.pbrt)
    else:
        spectrum = load_spectrum(spectrum_spec, lo=config.lo, hi=config.hi)
    reflectances = None
    if config.reflectances is not None:
        from wavelength_pdf.reflectances import load_reflectances

        reflectances = load_reflectances(config.reflectances, scene=scene, lo=config.lo, hi=config.hi,
                                         pbrt=config.pbrt)
    return spectrum, reflectances


def _pair(text: str) -> tuple[Path, str]:
    scene, sep, spectrum = text.partition("=")
    if not sep or not scene or not spectrum:
        raise ValueError(f"--pairs expects SCENE=SPECTRUM, got {text!r}")
    return Path(scene), spectrum


def cmd_grid(args) -> int:
    from wavelength_pdf.evaluation import report
    config = _config(args)
    jobs = list(itertools.product(args.scenes, args.spectra)) + [_pair(t) for t in args.pairs]
    if not jobs:
        raise ValueError("grid: give --scenes and --spectra, or --pairs")
    rows = run_grid(jobs, args.outdir, config, "evaluation grid", workers=args.workers, scheduler=args.scheduler)
    print(report.markdown_table(rows))
    print(f"report: {args.outdir / 'report.md'}")
    return 0


def default_shared() -> Path:
    """Where ``published`` looks for the shared material when ``--shared`` is not given: ../shared
    beside the checkout, or ``shared`` in the current folder for an installed package (whose
    ../shared would be beside site-packages)."""
    return REPO.parent / "shared" if data.in_checkout() else Path.cwd() / "shared"


def published_jobs(shared: Path, only: list[str] | None = None) -> list[tuple[Path, str]]:
    """The (scene, spectrum) pairs of the published comparison, as paths under ``shared``."""
    if not Path(shared).is_dir():
        raise FileNotFoundError(2, "no such folder: the published comparison needs the shared "
                                   "material (scenes/ and spectra/lspdd/); give its place with "
                                   "--shared DIR", str(shared))
    jobs = []
    for scene, spec, *_ in PUBLISHED:
        if only and f"{scene}/{spec}" not in only:
            continue
        path = shared / "scenes" / scene / "scene-v4.pbrt"
        spectrum = spec if ":" in spec else str(shared / "spectra" / "lspdd" / f"{spec}.csv")
        for f in (path, Path(spectrum) if ":" not in spectrum else None):
            if f is not None and not f.is_file():
                raise FileNotFoundError(2, f"missing: the published comparison needs the shared "
                                           f"material; is {shared} the right folder? (give it with "
                                           "--shared DIR)", str(f))
        jobs.append((path, spectrum))
    if not jobs:
        known = ", ".join(f"{s}/{p}" for s, p, *_ in PUBLISHED)
        raise ValueError(f"--only matches no job; the jobs are {known}")
    return jobs


def published_ratios(only: list[str] | None = None) -> list[str]:
    """The published baseline/table ratios of :func:`published_jobs`' jobs, in its order."""
    return [ratio for scene, spec, _, ratio in PUBLISHED if not only or f"{scene}/{spec}" in only]


def cmd_published(args) -> int:
    config = _config(args)
    jobs = published_jobs(args.shared, args.only)
    marks = published_ratios(args.only)
    run_grid(jobs, args.outdir, config, "published comparison at reduced resolution",
             workers=args.workers, scheduler=args.scheduler, published=marks)
    print((args.outdir / "results.md").read_text())
    print(f"report: {args.outdir / 'report.md'}")
    if args.docs is not None:
        copied = copy_report(args.outdir, args.docs)
        print(f"copied {len(copied)} files to {args.docs}")
    return 0


def copy_report(outdir: Path, dest: Path) -> list[Path]:
    """Copy a grid's report.md, results.csv and the images the report shows to ``dest``,
    keeping the folder layout so that the report's relative links still resolve. Nothing else
    goes: not the renders, not the tables, and not densities.png, which draws the lamp spectrum
    itself (licensed data such as the LSPDD spectra must not be redistributed)."""
    from wavelength_pdf.evaluation import report
    names = ["report.md", "results.csv", *report.report_images(outdir / "report.md")]
    copied = []
    for name in sorted(names):
        (dest / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(outdir / name, dest / name)
        copied.append(dest / name)
    return copied


def cmd_demo(args) -> int:
    from wavelength_pdf.evaluation import report
    config = _config(args)
    if args.scene == DEMO_SCENE:  # the demo scene in the renderer's own format
        args.scene = DEMO_SCENE.with_suffix(backend(args.renderer).scene_suffix)
    print(f"demo: {args.scene.relative_to(REPO) if args.scene.is_relative_to(REPO) else args.scene} "
          f"lit by {args.spectrum}; output in {args.outdir}", file=sys.stderr)
    with progress.bar(total=_images(config), desc="demo", file=sys.stderr, unit="image") as bar:
        ev = run_one(args.scene, args.spectrum, args.outdir, config, args.table, bar, args.renderer)
    print(report.markdown_table(ev.rows))
    print(f"table: {ev.table}\nresults: {args.outdir / 'results.csv'}\n"
          f"plots: {args.outdir / 'error-vs-spp-and-time.png'}, {args.outdir / 'error-maps.png'}, "
          f"{args.outdir / 'colour-bar.png'}")
    return 0
