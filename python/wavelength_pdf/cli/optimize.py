"""``wavelength-pdf optimize``: one spectrum (or a scene's emitters) to a table each."""
from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path
from typing import Sequence

from wavelength_pdf.cli import (EXIT_NOT_ACCEPTED, PROG, SPECTRUM_HELP, BadInput, Formatter,
                                check_solver, objective_args, range_args, solver_args)
from wavelength_pdf import extras
from wavelength_pdf.coverage import check_range
from wavelength_pdf.produce import make_grid, optimize_one, safe_name, summary_line
from wavelength_pdf.spectra import Spectrum, SpectrumError, load_spectra


def output_paths(spectra: Sequence[Spectrum], out: str) -> list[Path]:
    """Where each spectrum's table goes.

    One spectrum: ``out`` itself (or ``out/<name>.csv`` if ``out`` is a directory). Several
    (a scene with several emitters): ``out`` is a directory (existing, or ending in '/') that
    gets ``<name>.csv`` each, or a pattern with ``{name}`` and/or ``{index}``.
    """
    if not out.strip():
        raise BadInput("-o: empty output path")
    pattern = "{name}" in out or "{index}" in out
    is_dir = Path(out).is_dir() or out.endswith(("/", os.sep))
    if len(spectra) == 1 and not pattern:
        return [Path(out) / f"{safe_name(spectra[0].name)}.csv" if is_dir else Path(out)]
    if pattern:
        paths = [Path(out.format(name=safe_name(s.name), index=i)) for i, s in enumerate(spectra)]
    elif is_dir:
        paths = [Path(out) / f"{safe_name(s.name)}.csv" for s in spectra]
    else:
        names = ", ".join(s.name for s in spectra)
        raise BadInput(f"{len(spectra)} emitter spectra ({names}) but -o {out} is one file: "
                       f"give a directory (ending in '/') or a pattern with {{name}} or {{index}}")
    if len(set(paths)) != len(paths):
        raise BadInput(f"-o {out} gives the same file to several spectra: use {{index}}")
    return paths


def _suffix_path(path: str | None, spectrum: Spectrum, several: bool) -> Path | None:
    """An image path, made distinct per spectrum when there are several."""
    if path is None:
        return None
    if "{name}" in path:
        return Path(path.replace("{name}", safe_name(spectrum.name)))
    p = Path(path)
    if not several:
        return p
    return p.with_name(f"{p.stem}-{safe_name(spectrum.name)}{p.suffix}")


def budget(solver: str | None, grid, max_evals: int | None, objective: str = "J") -> int:
    """The evaluation budget the progress bar counts against."""
    from wavelength_pdf.optimize import DEFAULT_SOLVER, evaluation_budget

    return evaluation_budget(solver or DEFAULT_SOLVER, grid,
                             {"max_evals": max_evals} if max_evals else None, objective)


def whole_scene(spec: str, lo: float, hi: float, pbrt: str | None) -> Spectrum:
    """``--whole-scene``: the scene's total emission, from the renderer (design §5.6)."""
    from wavelength_pdf.scene_spectra import whole_scene_spectrum

    if not spec.lower().endswith(".pbrt"):
        raise BadInput(f"--whole-scene needs a pbrt-v4 scene (.pbrt), not {spec!r} (a scene's "
                       "emitters are summed; scene.pbrt#N picks one emitter instead)")
    return whole_scene_spectrum(spec, lo=lo, hi=hi, pbrt=pbrt)


def _scene_spec(spec: str) -> str | None:
    """The scene file of a ``.pbrt`` spectrum spec (``scene.pbrt#N`` included), else None."""
    base = spec.rsplit("#", 1)[0] if "#" in spec else spec
    return base if base.lower().endswith(".pbrt") else None


def surface_colours(choice: str | None, spec: str, lo: float, hi: float, pbrt: str | None):
    """The surface colours J is taken over (design §4.5), or None for one white surface.

    Without ``--reflectances``, a scene is optimized for its own materials (``scene``: on the
    Cornell box under the compact fluorescent lamp it measured better than the white surface,
    docs/whole-scenes.md); when the renderer cannot give them (none found, or no diffuse
    material) a warning says so and the white surface is used. Other spectra use the white
    surface unless ``--reflectances`` says otherwise; ``white`` asks for it explicitly."""
    from wavelength_pdf.renderer import RendererNotFound
    from wavelength_pdf.reflectances import load_reflectances

    if choice == "white":
        return None
    scene = _scene_spec(spec)
    if choice is None:
        if scene is None:
            return None
        try:
            return load_reflectances("scene", scene=scene, lo=lo, hi=hi, pbrt=pbrt)
        except (RendererNotFound, SpectrumError) as e:
            print(f"{PROG}: warning: optimizing for a white surface: the scene's material "
                  f"reflectances are not available ({e}); give --reflectances white to choose "
                  "it", file=sys.stderr)
            return None
    return load_reflectances(choice, scene=scene, lo=lo, hi=hi, pbrt=pbrt)


def cmd_optimize(args: argparse.Namespace) -> int:
    from wavelength_pdf.progress import OptimizationProgress

    lo, hi = args.range
    grid = make_grid(lo, hi, args.grid_step)
    check_solver(args.solver)
    objective, objective_spp = objective_args(args)
    if args.plot or args.colour_bar:
        extras.require("plots", "--plot and --colour-bar")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if args.whole_scene:
            spectra = [whole_scene(args.spectrum, lo, hi, args.pbrt)]
        else:
            if args.pbrt is not None and not _scene_spec(args.spectrum):
                raise BadInput("--pbrt is only used with a scene (--whole-scene, --reflectances "
                               "scene or a .pbrt spectrum)")
            spectra = load_spectra(args.spectrum, lo=lo, hi=hi)
    for w in caught:
        print(f"{PROG}: warning: {w.message}", file=sys.stderr)
    # Light outside the table's range (design §3.3): refused above 1 %, warned about above
    # the reporting thresholds, for every spectrum before any of them is optimized.
    for sp in spectra:
        for w in check_range(sp, lo, hi):
            print(f"{PROG}: warning: {w}", file=sys.stderr)
    reflectances = surface_colours(args.reflectances, args.spectrum, lo, hi, args.pbrt)
    paths = output_paths(spectra, args.output)
    several = len(spectra) > 1
    total = budget(args.solver, grid, args.max_evals, objective)
    status = 0
    for sp, path in zip(spectra, paths):
        bar = OptimizationProgress(sp.name, total, enabled=not args.quiet)
        try:
            out = optimize_one(sp, path, grid, args.solver, args.seed, args.max_seconds, bar,
                               _suffix_path(args.colour_bar, sp, several),
                               _suffix_path(args.plot, sp, several), max_evals=args.max_evals,
                               reflectances=reflectances, objective=objective,
                               objective_spp=objective_spp)
        finally:
            bar.close()
        print(summary_line(out.result, path if out.written else None))
        if not out.written:
            print(f"{PROG}: {sp.name}: result not accepted ({out.result.reason}); table not "
                  "written", file=sys.stderr)
            status = EXIT_NOT_ACCEPTED
    return status


def add_parser(sub, names: list[str]) -> None:
    from wavelength_pdf.cli.cache import help_text

    o = sub.add_parser("optimize", formatter_class=Formatter, epilog=help_text(),
                       help="optimize the wavelength table of a spectrum",
                       description="Optimize four wavelength densities for SPECTRUM and "
                                   "write them as a table (design §2) with a comment header. "
                                   "A result that is not accepted (biased, a channel's std "
                                   "worse than the initialization's, or J worse than "
                                   "stratified uniform sampling's) is not written (exit 1). "
                                   "Which to use when: for a spiky lamp, stratified sampling of "
                                   "its own emission already gives most of the gain with nothing "
                                   "to install (pbrt --wavelength-sampling emission; Mitsuba: "
                                   "wavelength_pdf.mitsuba.emission_srf; the same table as a "
                                   "file: wavelength-pdf baseline spd SCENE --whole-scene --range "
                                   "360 830); an optimized table is the refinement, where the "
                                   "benchmark (docs/benchmark.md) shows it pays.")
    o.add_argument("spectrum", metavar="SPECTRUM", help=SPECTRUM_HELP)
    o.add_argument("-o", "--output", required=True, metavar="TABLE",
                   help="output table (.csv); for a scene with several emitters, a "
                        "directory (ending in '/') or a pattern with {name} or {index}")
    o.add_argument("--whole-scene", action="store_true",
                   help="SPECTRUM is a pbrt-v4 scene: write ONE table for the light of the "
                        "whole scene, every emitter's spectrum weighted by the power it emits "
                        "there, as the renderer computes it (pbrt --emission-spectrum, "
                        "design §5.6); the table covers every lamp")
    o.add_argument("--reflectances", metavar="SET", default=None,
                   help="optimize for coloured surfaces instead of one white (design §4.5): J "
                        "is the mean of each colour's J and the health rules hold for every "
                        "colour. SET: 'scene' (the materials of the .pbrt scene, as the "
                        "renderer builds them; the default for a .pbrt SPECTRUM, falling back "
                        "to white with a warning when the renderer cannot give them), "
                        "'colorchecker' (the 24 patches colour-science ships), 'white' (one "
                        "white surface, design §4.1; the default for other spectra) or a CSV "
                        "file (design §3.4: a wavelength column, then one column per "
                        "reflectance)")
    o.add_argument("--pbrt", metavar="PATH", default=None,
                   help="with --whole-scene or --reflectances scene: the renderer (default: $WAVELENGTH_PDF_PBRT, "
                        "else the checkout's build/pbrt, else the wheel's own, else pbrt on PATH)")
    solver_args(o, names)
    range_args(o)
    o.add_argument("--colour-bar", "--color-bar", dest="colour_bar", metavar="PNG",
                   help="also write a colour bar image: the estimated colour for every u "
                        "(rows: initialization, result, target)")
    o.add_argument("--plot", metavar="PNG",
                   help="also write a plot of the four densities over the spectrum")
    o.set_defaults(func=cmd_optimize)
