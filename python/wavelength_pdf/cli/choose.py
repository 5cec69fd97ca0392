"""``wavelength-pdf choose SCENE.pbrt [TABLE.csv ...]``: which table for this scene, by its
predicted image error (wavelength_pdf.evaluation.choose, design §6.8); ``wavelength-pdf
choose-guiding SCENE.pbrt SPECTRA [NAME=]TABLES...``: the same for each of wavelength guiding's
mixtures (wavelength_pdf.evaluation.guiding_choice)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wavelength_pdf.cli import BadInput, Formatter, out_folder, positive_int

#: The polish's default budget (wavelength_pdf.solvers.REFINE_EVALUATIONS), written out so
#: that ``--help`` imports no solver; a test holds the two equal.
REFINE_EVALUATIONS = 200


def cmd_choose(args: argparse.Namespace) -> int:
    from wavelength_pdf.evaluation.choose import predict_tables
    from wavelength_pdf.table import read_table, write_table

    if not args.scene.is_file():
        raise BadInput(f"{args.scene}: no such scene file")
    if not args.tables and args.no_simple and not args.polish:
        raise BadInput("nothing to compare: give tables, drop --no-simple or add --polish")
    if args.resolution_scale is None:
        args.resolution_scale = 1.0 if args.spread else 0.1
    if not 0 < args.resolution_scale <= 1:
        raise BadInput(f"--resolution-scale must lie in (0, 1], not {args.resolution_scale:g}")
    if args.spread and args.resolution_scale != 1:
        raise BadInput("--spread measures the pixels you render: it needs the scene's own film size "
                       f"(--resolution-scale 1), not {args.resolution_scale:g} of it")
    _check_polish(args)
    tables = {}
    for path in args.tables:
        tables[str(path)] = read_table(path)  # every table read (and refused) before any render
    workdir = args.workdir or out_folder() / "choose" / args.scene.resolve().parent.name / args.scene.stem
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    preds = predict_tables(args.scene, tables, args.spp, workdir, pixel_sampler=args.pixel_sampler,
                           resolution=args.resolution_scale, pbrt=args.pbrt, transfer_spp=args.transfer_spp,
                           simple=not args.no_simple, polish=args.polish, spread=args.spread,
                           polish_evaluations=args.polish_evaluations, say=say)
    width = max(len(p.name) for p in preds)
    print(f"{args.scene} at {args.spp} spp ({args.pixel_sampler}): predicted mean squared CIEDE2000 over "
          f"the lit pixels")
    print(f"  {'table':<{width}}  {'wavelengths':>11}  {'with paths':>10}")
    for p in preds:
        print(f"  {p.name:<{width}}  {p.wavelength:11.4g}  {p.total:10.4g}")
    best = preds[0]
    print(f"best: {best.name}")
    if args.output:
        from wavelength_pdf.table import Table

        note = (f"chosen by wavelength-pdf choose for {args.scene} at {args.spp} spp ({args.pixel_sampler}): "
                f"predicted de2 {best.total:.4g}, of {len(preds)} candidates")
        write_table(args.output, Table(best.table.grid, best.table.pdfs, [*best.table.comments, note]))
        print(f"wrote {args.output}")
    return 0


def cmd_choose_guiding(args: argparse.Namespace) -> int:
    from wavelength_pdf.evaluation.guiding_choice import EMISSION, choose_guiding_tables

    if not args.scene.is_file():
        raise BadInput(f"{args.scene}: no such scene file")
    if not 0 < args.resolution_scale <= 1:
        raise BadInput(f"--resolution-scale must lie in (0, 1], not {args.resolution_scale:g}")
    if not 0 <= args.margin < 1:
        raise BadInput(f"--margin must lie in [0, 1), not {args.margin:g}")
    _check_polish(args)
    if not args.candidates and not args.polish:
        raise BadInput("nothing to choose from: give folders of optimized tables (TABLES) or --polish")
    candidates = {}
    for c in args.candidates:
        name, _, folder = c.rpartition("=") if "=" in c else (Path(c).name, "", c)
        if not name or name in candidates:
            raise BadInput(f"{c!r}: give each folder of tables once, with a name of its own (NAME=FOLDER)")
        candidates[name] = Path(folder)
    workdir = args.workdir or out_folder() / "choose" / args.scene.resolve().parent.name / args.scene.stem
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    try:
        choices = choose_guiding_tables(args.scene, args.spectra, candidates, args.spp, args.output, workdir,
                                        margin=args.margin, pixel_sampler=args.pixel_sampler,
                                        resolution=args.resolution_scale,
                                        pbrt=args.pbrt, transfer_spp=args.transfer_spp, polish=args.polish,
                                        polish_evaluations=args.polish_evaluations, say=say)
    except ValueError as e:
        raise BadInput(str(e)) from None
    names = list(dict.fromkeys([EMISSION, *candidates, *(n for c in choices for n in c.predicted)]))
    print(f"{args.scene} at {args.spp} spp ({args.pixel_sampler}): each guiding table's predicted mean squared "
          "CIEDE2000 of its wavelengths over its pixels")
    widths = [max(10, len(n)) for n in names]
    print("  table  pixels  " + "  ".join(f"{n:>{w}}" for n, w in zip(names, widths)) + "  chosen")
    for c in choices:
        cells = "  ".join(f"{c.predicted[n]:{w}.4g}" if n in c.predicted else f"{'-':>{w}}"
                          for n, w in zip(names, widths))
        print(f"  {c.table:5d}  {c.pixels:6d}  {cells}  {c.chosen}")
    kept = sum(c.chosen != EMISSION for c in choices)
    print(f"wrote {args.output}: {kept} optimized table(s) of {len(choices)} and choice.csv")
    if not kept:
        print("every table keeps its emission table: render without --wavelength-guiding-tables")
    return 0


def _check_polish(args: argparse.Namespace) -> None:
    """``--polish`` and its budget, as both commands take them (before any render)."""
    if args.polish and args.pixel_sampler != "sobol":
        raise BadInput("--polish models the low-discrepancy pixel sampler (--pixel-sampler sobol)")
    if args.polish_evaluations is not None and not args.polish:
        raise BadInput("--polish-evaluations is the polish's budget: give --polish too")


def _prediction_options(c, resolution: float) -> None:
    """The options of the prediction's renders, shared by choose and choose-guiding."""
    c.add_argument("--spp", type=positive_int, default=64, help="the samples per pixel you render at (a power of "
                   "two with the low-discrepancy sampler; default 64)")
    c.add_argument("--pixel-sampler", choices=("sobol", "independent"), default="sobol",
                   help="your pixel sampler: low-discrepancy (pbrt-v4's sobol and zsobol samplers; default) "
                        "or independent")
    c.add_argument("--resolution-scale", type=float, default=resolution, metavar="F",
                   help="the renders' film size as a share of the scene's (default "
                        + (f"{resolution:g})" if resolution else "0.1, with --spread 1)"))
    c.add_argument("--transfer-spp", type=positive_int, default=1024, metavar="N",
                   help="samples per pixel of the spectral render (default 1024)")
    c.add_argument("--workdir", type=Path, default=None, metavar="DIR",
                   help="where the renders go, kept for the next run (default out/choose/FOLDER/SCENE)")
    c.add_argument("--pbrt", type=Path, default=None, help="the renderer (default: as design §7)")
    c.add_argument("--polish-evaluations", type=positive_int, default=None, metavar="N",
                   help="with --polish: each polish's budget of objective evaluations (default "
                        f"{REFINE_EVALUATIONS}; fewer are faster and may stop short of the best table)")
    c.add_argument("--quiet", action="store_true", help="no progress messages")


def add_parser(sub) -> None:
    c = sub.add_parser(
        "choose", formatter_class=Formatter,
        help="which table for this scene: each candidate's image error, predicted from three renders",
        description="Predicts the image error (mean squared CIEDE2000 over the lit pixels, at the spp you "
                    "render at) of each table given and of the simple samplers of the scene's lamp "
                    "(uniform, visible, spd, luminance, xyz), from three renders of a copy of the scene "
                    "under a flat lamp (a spectral film at 1024 spp and a seed pair at 64 spp, at a tenth "
                    "of its size; design §6.8), and prints them best first; -o writes the best. The scene "
                    "must be lit by one kind of light (emitters whose spectra are equal up to scale). Over "
                    "the benchmark's scene sweep its choice was never worse than the best simple sampler by "
                    "more than 10 % (docs/benchmark.md). --polish adds tables polished for the scene's pixels "
                    "(from the lamp's own spd table, and from each table given), --spread the spectra each "
                    "pixel's paths see (at the edges of what it shows, and off differently coloured walls).")
    c.add_argument("scene", type=Path, metavar="SCENE.pbrt", help="a pbrt-v4 scene lit by one kind of light")
    c.add_argument("tables", type=Path, nargs="*", metavar="TABLE.csv", help="tables to compare (design §2)")
    c.add_argument("--no-simple", action="store_true", help="compare the given tables only")
    c.add_argument("-o", "--output", type=Path, default=None, metavar="BEST.csv", help="write the best table here")
    c.add_argument("--polish", action="store_true",
                   help="also the spd table and each given table polished for the scene's pixels at --spp "
                        "(the pixels objective, design §4.6; seconds each, no optimizer run needed; below "
                        "64 spp each also polished at 64 spp first)")
    c.add_argument("--spread", action="store_true",
                   help="predict with each pixel's spread (the spectra its paths see, two or more at an edge or "
                        "off coloured walls; design §6.8) from two renders of the same paths at independent "
                        "wavelengths, one path per sub-pixel at 8 x 8 sub-pixels, each at many wavelengths: measured "
                        "at the scene's own film size, so the renders cost more than at the default tenth (about 6 "
                        "minutes for a 320 x 240 film on two cores, docs/benchmark.md)")
    _prediction_options(c, None)
    c.set_defaults(func=cmd_choose, extra="evaluation")

    g = sub.add_parser(
        "choose-guiding", formatter_class=Formatter,
        help="for each of wavelength guiding's mixtures, its emission table or an optimized one, by the "
             "predicted image error over the pixels it lights",
        description="Wavelength guiding (pbrt --wavelength-guiding) gives each tile the table of its light "
                    "mixture. This predicts, for each mixture, the image error over the pixels it lights "
                    "(design §6.8: a copy of the scene per kind of light gives each pixel's light along "
                    "that kind's own paths) of its emission table and of each folder's "
                    "optimized table, as the renderer samples them (defensive share included), and writes "
                    "the winners to OUT for pbrt --wavelength-guiding-tables OUT (mixtures whose emission "
                    "table wins have no file there) with OUT/choice.csv. SPECTRA is the folder pbrt "
                    "--wavelength-guiding --wavelength-guiding-spectra SPECTRA wrote at the render's own "
                    "settings; the TABLES folders are wavelength-pdf batch SPECTRA -o TABLES outputs "
                    "(e.g. optimized for the white surface and for the scene's materials). docs/guiding.md.")
    g.add_argument("scene", type=Path, metavar="SCENE.pbrt", help="the pbrt-v4 scene")
    g.add_argument("spectra", type=Path, metavar="SPECTRA", help="the folder --wavelength-guiding-spectra wrote")
    g.add_argument("candidates", nargs="*", metavar="[NAME=]TABLES",
                   help="folders of optimized mixture tables (mixture-HASH.csv), named by NAME or the folder's "
                        "name (none with --polish: the emission tables polished, no optimizer run)")
    g.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="the folder to write (replaced when it holds an earlier choice)")
    g.add_argument("--margin", type=float, default=0.1, metavar="F",
                   help="keep an optimized table only where its predicted error is below (1 - F) times the "
                        "emission table's (default 0.1: the prediction is an approximation in scenes with "
                        "several kinds of light)")
    g.add_argument("--polish", action="store_true",
                   help="also each mixture's emission table and each folder's table polished for the pixels "
                        "of its guiding table at --spp (the pixels objective, design §4.6; seconds each)")
    _prediction_options(g, 0.5)
    g.set_defaults(func=cmd_choose_guiding, extra="evaluation")
