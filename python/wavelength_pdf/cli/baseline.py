"""``wavelength-pdf baseline``: the simple samplers as tables (design §1.7), no optimizer.

Every sampler the benchmark compares (docs/benchmark.md) is a table read by the same code, so
that a comparison is of distributions and nothing else; this command writes any of them for
any renderer that reads tables.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wavelength_pdf.cli import PROG, SPECTRUM_HELP, BadInput, Formatter
from wavelength_pdf.cli.optimize import _scene_spec, output_paths, whole_scene
from wavelength_pdf.model import RANGE
from wavelength_pdf.stratified import METHODS, VISIBLE_RANGE_PBRT

#: Methods that read a spectrum.
NEEDS_SPECTRUM = ("spd", "luminance", "xyz", "start")
ALL_METHODS = (*METHODS, "start")

METHOD_HELP = {
    "uniform": "stratified uniform sampling of the range: four bands of equal width",
    "visible": "pbrt-v4's visible sampling, sech^2(0.0072 (lambda - 538)), as a table over "
               f"{VISIBLE_RANGE_PBRT[0]:g}-{VISIBLE_RANGE_PBRT[1]:g} nm unless --range is given",
    "spd": "stratified sampling of the spectrum: four bands of equal power (Evans and McCool 1999)",
    "luminance": "stratified sampling of the spectrum times the luminance curve ybar",
    "xyz": "stratified sampling of the spectrum times xbar + ybar + zbar",
    "start": "the optimizer's starting point: the equal-mass partition of the spectrum times "
             "xbar + ybar + zbar on the grid optimize would choose (what optimize starts from)",
}


def make_tables(method: str, spec: str | None, lo: float, hi: float, *, whole: bool = False,
                pbrt: str | None = None, range_given: bool = True):
    """The tables of ``method`` (one per spectrum of ``spec``; one for the range-only methods)."""
    from wavelength_pdf import stratified
    from wavelength_pdf.spectra import load_spectra

    if method not in ALL_METHODS:
        raise BadInput(f"unknown method {method!r}; choose from {', '.join(ALL_METHODS)}")
    if method in ("uniform", "visible"):
        if spec is not None or whole:
            raise BadInput(f"the method {method!r} takes no SPECTRUM (it samples a fixed density)")
        if method == "uniform":
            return [("uniform", stratified.uniform_table(lo, hi))]
        return [("visible", stratified.visible_table(*((lo, hi) if range_given else VISIBLE_RANGE_PBRT)))]
    if spec is None:
        raise BadInput(f"the method {method!r} needs a SPECTRUM")
    spectra = [whole_scene(spec, lo, hi, pbrt)] if whole else load_spectra(spec, lo=lo, hi=hi)
    out = []
    for sp in spectra:
        if method == "start":
            from wavelength_pdf.optimize import starting_table

            out.append((sp.name, starting_table(sp)))
        else:
            out.append((sp.name, stratified.stratified_table(sp, method, lo, hi)))
    return out


def cmd_baseline(args: argparse.Namespace) -> int:
    from wavelength_pdf.produce import check_output_path
    from wavelength_pdf.table import write_table

    lo, hi = args.range if args.range is not None else RANGE
    if args.pbrt is not None and not (args.whole_scene or (args.spectrum and _scene_spec(args.spectrum))):
        raise BadInput("--pbrt is only used with --whole-scene")
    tables = make_tables(args.method, args.spectrum, lo, hi, whole=args.whole_scene, pbrt=args.pbrt,
                         range_given=args.range is not None)

    class _Named:  # output_paths names a file per spectrum by .name
        def __init__(self, name):
            self.name = name

    paths = output_paths([_Named(n) for n, _ in tables], args.output)
    for p in paths:
        check_output_path(p)
    for (name, table), path in zip(tables, paths):
        path.parent.mkdir(parents=True, exist_ok=True)
        write_table(path, table)
        print(f"{name}: {args.method} -> {path} ({table.grid.size} nodes, "
              f"{table.grid[0]:g}-{table.grid[-1]:g} nm)")
    return 0


def add_parser(sub) -> None:
    b = sub.add_parser("baseline", formatter_class=Formatter,
                       help="write a simple sampler as a table (stratified spectrum, uniform, "
                            "visible, the optimizer's start)",
                       description="Write one of the simple wavelength samplers as an ordinary "
                                   "table (design §1.7, §2), with no optimization: the samplers "
                                   "the benchmark compares every optimized table with "
                                   "(docs/benchmark.md). Methods: " +
                                   "; ".join(f"{m}: {h}" for m, h in METHOD_HELP.items()) + ". "
                                   "'spd SCENE.pbrt --whole-scene --range 360 830' writes the "
                                   "table that pbrt --wavelength-sampling emission builds in "
                                   "memory (pbrt --emission-table writes it too), for renderers "
                                   "that only read tables.")
    b.add_argument("method", metavar="METHOD", choices=ALL_METHODS,
                   help="one of " + ", ".join(ALL_METHODS))
    b.add_argument("spectrum", metavar="SPECTRUM", nargs="?", default=None,
                   help=SPECTRUM_HELP + " (for spd, luminance, xyz and start)")
    b.add_argument("-o", "--output", required=True, metavar="TABLE",
                   help="output table (.csv); for a scene with several emitters, a directory "
                        "(ending in '/') or a pattern with {name} or {index}")
    b.add_argument("--range", nargs=2, type=float, metavar=("LO", "HI"), default=None,
                   help=f"wavelength range of the table, nm (default {RANGE[0]:g} {RANGE[1]:g}; "
                        f"visible: {VISIBLE_RANGE_PBRT[0]:g} {VISIBLE_RANGE_PBRT[1]:g})")
    b.add_argument("--whole-scene", action="store_true",
                   help="SPECTRUM is a pbrt-v4 scene: one table for its total emission, every "
                        "emitter weighted by the power it emits (pbrt --emission-spectrum, "
                        "design §5.6)")
    b.add_argument("--pbrt", metavar="PATH", default=None,
                   help="with --whole-scene: the renderer (default: $WAVELENGTH_PDF_PBRT, else "
                        "the checkout's build/pbrt, else the wheel's own, else pbrt on PATH)")
    b.set_defaults(func=cmd_baseline)
