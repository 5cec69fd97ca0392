"""The ``wavelength-pdf`` command: a thin layer over the library, one module per command group.

Commands
--------
optimize SPECTRUM -o TABLE
    Optimize the four wavelength densities for one spectrum (or one per distinct emitter of a
    pbrt-v4 scene) and write the table(s) with a comment header (:mod:`.optimize`).
baseline METHOD [SPECTRUM] -o TABLE
    A simple sampler as a table, no optimizer: stratified sampling of the spectrum (spd,
    luminance, xyz), stratified uniform, pbrt-v4's visible density, the optimizer's start
    (:mod:`.baseline`, design §1.7).
batch FOLDER -o OUTDIR
    Every spectrum file of a folder to a table each plus ``summary.csv``; parallel and
    resumable (:mod:`.batch`, over :mod:`wavelength_pdf.batch`).
show TABLE
    Print a table's grid and normalization and, with ``--spectrum``, its objective and
    estimator health (:mod:`.show`).
evaluate, grid, published, demo
    The evaluation (design §6; :mod:`wavelength_pdf.cli.evaluate`).
mitsuba SCENE.xml
    Render a Mitsuba 3 XML scene with the ``wavelength_table`` plugin registered (Mitsuba's
    own command cannot load it; :mod:`.mitsuba`).
cache info|clear|warm
    The optimizer's compile cache: its place and size, emptied, or filled ahead of time
    (:mod:`.cache`, design §7).

Bad input (a malformed or missing spectrum, scene or table) prints ``wavelength-pdf:
<file:line: reason>`` and exits with status 2; a result that is not accepted is not written
and exits with status 1.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Sequence

from wavelength_pdf import extras
from wavelength_pdf._version import __version__
from wavelength_pdf.model import MAX_TABLE_NODES, RANGE
from wavelength_pdf.spectra import SpectrumError
from wavelength_pdf.table import TableError

PROG = "wavelength-pdf"

#: Exit status for bad input (a usage error, like argparse's).
EXIT_BAD_INPUT = 2
#: Exit status for a result that is not accepted.
EXIT_NOT_ACCEPTED = 1


class BadInput(Exception):
    """A command-line input problem that is not a spectrum or table error."""


def solver_names() -> list[str]:
    """Names in the solver registry (empty if the registry cannot be imported)."""
    try:
        from wavelength_pdf.solvers import SOLVERS
    except Exception:  # the registry is optional for --help; optimize reports the error
        return []
    return list(SOLVERS)


def check_solver(name: str | None) -> None:
    if name is None:
        return
    names = solver_names()
    if names and name not in names:
        raise BadInput(f"unknown solver {name!r}; choose one of: {', '.join(names)}")


SPECTRUM_HELP = ("a spectrum: an LSPDD export (.csv), a pbrt .spd file, a pbrt-v4 scene "
                  "(.pbrt: one table per distinct emitter spectrum; scene.pbrt#N picks one), "
                  "cie:NAME (colour-science illuminant, e.g. cie:FL11) or lamp:NAME "
                  "(colour-science light source)")


class Formatter(argparse.HelpFormatter):
    """argparse's formatter without breaking lines at hyphens (solver names stay whole)."""

    def _split_lines(self, text: str, width: int) -> list[str]:
        import textwrap

        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        import textwrap

        return textwrap.fill(" ".join(text.split()), width, initial_indent=indent,
                             subsequent_indent=indent, break_on_hyphens=False)


def range_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--range", nargs=2, type=float, metavar=("LO", "HI"),
                        default=RANGE,
                        help=f"wavelength range of the table, nm (default: {RANGE[0]:g} {RANGE[1]:g})")
    parser.add_argument("--grid-step", default="auto", metavar="NM",
                        help="spacing of the table's nodes, nm, which must divide the range "
                             f"and give at most {MAX_TABLE_NODES} nodes (design §2.3); "
                             "or 'auto' (default): 5 nm over 380-780, refined around the lines "
                             "of a line lamp where that lowers J")


def _default_solver() -> str:
    try:
        from wavelength_pdf.solvers import DEFAULT_SOLVER
    except Exception:
        return "the package's default strategy"
    return str(DEFAULT_SOLVER)


def solver_args(parser: argparse.ArgumentParser, names: list[str]) -> None:
    listing = ", ".join(names) if names else "see wavelength_pdf.solvers.SOLVERS"
    parser.add_argument("--solver", default=None, metavar="NAME",
                        help=f"solver from the registry: {listing} (default: "
                             f"{_default_solver()})")
    parser.add_argument("--seed", type=int, default=0, metavar="N",
                        help="random seed; same input and seed give the same table "
                             "(default: 0)")
    parser.add_argument("--max-seconds", type=positive_seconds, default=None, metavar="S",
                        help="cap on the wall time per spectrum, seconds, counted from its "
                             "start (compiling included; design §7); the best table found so "
                             "far is kept, judged like any other (default: the solver's own "
                             "evaluation budget, which keeps results reproducible)")
    parser.add_argument("--max-evals", type=positive_int, default=None, metavar="N",
                        help="the solver's evaluation budget per spectrum (default: the "
                             "solver's own); same input, seed and budget give the same table; a "
                             "multistage result above 0.05 x uniform J gets a second search of "
                             "1.5 N with more starts kept")
    objective_options(parser, "what to minimize")
    parser.add_argument("--quiet", "-q", action="store_true",
                        help="no progress bar (the one-line summary is still printed)")


def objective_options(parser: argparse.ArgumentParser, what: str) -> None:
    """``--objective`` and ``--objective-spp`` (design §4.6); ``what`` starts the help."""
    parser.add_argument("--objective", default="J", metavar="NAME",
                        help=f"{what} (design §4.6): 'J', the mean CIEDE2000 of one "
                             "path's colour on a white surface (§4.1), or 'stratified', the "
                             "linearised CIEDE2000 of a pixel's mean of --objective-spp "
                             "stratified samples (default: J)")
    parser.add_argument("--objective-spp", type=positive_int, default=None, metavar="N",
                        help="with --objective stratified: the samples per pixel it models, "
                             "1..4096 (default: 64)")


def objective_args(args: argparse.Namespace) -> tuple[str, int]:
    """``--objective`` and ``--objective-spp`` checked (before any long work): (name, spp)."""
    from wavelength_pdf.problem import DEFAULT_OBJECTIVE_SPP, check_objective

    spp = DEFAULT_OBJECTIVE_SPP if args.objective_spp is None else args.objective_spp
    if args.objective_spp is not None and args.objective != "stratified":
        raise BadInput(f"--objective-spp is only used with --objective stratified, not {args.objective!r}")
    try:
        check_objective(args.objective, spp)
    except ValueError as e:
        raise BadInput(f"--objective: {e}") from None
    return args.objective, spp


def positive_seconds(text: str) -> float:
    """``--max-seconds``: a finite number of seconds > 0 (not 0, negative, nan or inf)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0, got {text!r}")
    return v


def positive_int(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {n}")
    return n


def out_folder() -> Path:
    """The evaluation's default output folder: the checkout's ``out/`` when running from one,
    else ``./out``."""
    from wavelength_pdf import data

    return (data.CHECKOUT if data.in_checkout() else Path.cwd()) / "out"


def cluster_args(p: argparse.ArgumentParser) -> None:
    """--workers N | --scheduler ADDRESS: where the renders of an evaluation run (Dask)."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, metavar="N",
                       help="run the renders on a local Dask cluster of N single-threaded worker processes, "
                            "each render using cores/N threads (default: one worker per core)")
    where.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                       help="run the renders on the existing Dask cluster at this scheduler (workers started "
                            "with `dask worker`; they must see the output folder, the scenes and the renderer "
                            "at the same paths): docs/evaluation.md")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``wavelength-pdf`` (optimize, batch, show, evaluate, grid, demo)."""
    from wavelength_pdf.cli import baseline, batch, cache, mitsuba, optimize, show

    names = solver_names()
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=Formatter,
        description="Optimized wavelength-sampling densities for spectral rendering under "
                    "spiky lamps: four piecewise-linear densities whose balance-heuristic "
                    "colour estimate varies least in CIEDE2000 (Dobos 2025, \"Perception-based "
                    "Optimization of Wavelength Sampling Distributions for Spectral "
                    "Rendering\", TU Delft; the contracts are in docs/design.md).",
        epilog="solvers: " + (", ".join(names) if names else "(registry unavailable)") +
               ". Bad input exits with status 2, a result that is not accepted with 1. "
               + cache.help_text(),
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND",
                           title="commands (run 'wavelength-pdf COMMAND --help' for details)")
    optimize.add_parser(sub, names)
    baseline.add_parser(sub)
    batch.add_parser(sub, names)
    show.add_parser(sub)
    cache.add_parser(sub)
    mitsuba.add_parser(sub)

    # The evaluation (design §6): evaluate, grid, published and demo (the README's main job).
    from wavelength_pdf.cli import benchmark, choose
    from wavelength_pdf.cli.evaluate import add_subcommands

    add_subcommands(sub)
    benchmark.add_parser(sub, out_folder())
    choose.add_parser(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``wavelength-pdf``; returns the exit status."""
    from wavelength_pdf.threads import pin_xla_threads

    pin_xla_threads()  # before JAX starts: results independent of the number of cores
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if getattr(args, "extra", None):  # a command of an optional part (wavelength_pdf.extras)
            extras.require(args.extra, f"'{PROG} {args.command}'")
        return int(args.func(args) or 0)
    except (SpectrumError, TableError, BadInput, ValueError) as e:
        # ValueError: input the numerical core rejects (e.g. a spectrum with no luminance).
        print(f"{PROG}: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:  # missing file or folder, permission denied, disk full
        where = f"{e.filename}: " if e.filename else ""
        print(f"{PROG}: {where}{e.strerror or e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as e:  # the renderer failed, or an evaluation's table was not accepted
        print(f"{PROG}: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
