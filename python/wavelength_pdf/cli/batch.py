"""``wavelength-pdf batch``: a folder of spectra to tables and ``summary.csv``."""
from __future__ import annotations

import argparse
import sys
from typing import Any

from wavelength_pdf.cli import (positive_int, EXIT_BAD_INPUT, EXIT_NOT_ACCEPTED, PROG, BadInput, Formatter,
                                check_solver, objective_args, range_args, solver_args)
from wavelength_pdf.produce import make_grid


def cmd_batch(args: argparse.Namespace) -> int:
    from wavelength_pdf.batch import BatchError, run_batch

    lo, hi = args.range
    grid = make_grid(lo, hi, args.grid_step)
    check_solver(args.solver)
    objective, objective_spp = objective_args(args)
    reflectances = _colours(args.reflectances, lo, hi)
    state: dict[str, Any] = {"bar": None}

    def start(n: int) -> None:
        if not args.quiet and n:
            from tqdm import tqdm

            state["bar"] = tqdm(total=n, desc="batch", unit="spectrum", file=sys.stderr,
                                disable=None)

    def row(r: dict) -> None:
        _report(r, state["bar"], args.quiet)

    try:
        rows, summary = run_batch(args.folder, args.output, lo=lo, hi=hi, grid=grid,
                                  solver=args.solver, seed=args.seed,
                                  max_seconds=args.max_seconds, max_evals=args.max_evals,
                                  objective=objective, objective_spp=objective_spp,
                                  reflectances=reflectances, jobs=max(1, args.jobs or 1),
                                  force=args.force,
                                  on_start=start, on_row=row)
    except BatchError as e:
        raise BadInput(str(e)) from None
    finally:
        if state["bar"] is not None:
            state["bar"].close()
    bad = [r for r in rows if r["status"] not in ("written", "kept")]
    print(f"{len(rows) - len(bad)}/{len(rows)} tables in {args.output} "
          f"({sum(r['status'] == 'kept' for r in rows)} kept from an earlier run); "
          f"summary: {summary}")
    if any(r["status"] == "error" for r in bad):
        return EXIT_BAD_INPUT
    return EXIT_NOT_ACCEPTED if bad else 0


def _colours(choice: str, lo: float, hi: float):
    """``--reflectances``: None for the white surface, else the set (read before any work)."""
    from wavelength_pdf.reflectances import WHITE, load_reflectances
    from wavelength_pdf.spectra import SpectrumError

    if choice == WHITE:
        return None
    if choice == "scene":
        raise BadInput("--reflectances scene is optimize's, for one .pbrt scene; batch takes "
                       "'white', 'colorchecker' or a CSV file of reflectances")
    try:
        return load_reflectances(choice, lo=lo, hi=hi)
    except (SpectrumError, OSError) as e:
        raise BadInput(f"--reflectances: {e}") from None


def _report(row: dict[str, Any], bar, quiet: bool) -> None:
    if row["status"] != "written":
        msg = f"{PROG}: {row['input']}: {row['status']}: {row['message']}"
        (bar.write(msg, file=sys.stderr) if bar is not None else print(msg, file=sys.stderr))
    elif not quiet:
        msg = (f"{row['name']}: J {row['J']} ({row['J_over_uniform']} x uniform), "
               f"{float(row['seconds'] or 0):.1f} s -> {row['table']}")
        (bar.write(msg, file=sys.stderr) if bar is not None else print(msg))
    if bar is not None:
        bar.update(1)


def add_parser(sub, names: list[str]) -> None:
    b = sub.add_parser("batch", formatter_class=Formatter,
                       help="optimize every spectrum file of a folder",
                       description="Optimize every spectrum file (.csv, .spd, .pbrt) in "
                                   "FOLDER to a table each in OUTDIR, plus OUTDIR/summary.csv. "
                                   "Resumable: a table newer than its input is kept.")
    b.add_argument("folder", metavar="FOLDER", help="folder of spectrum files")
    b.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="output folder for the tables and summary.csv")
    b.add_argument("--jobs", "-j", type=positive_int, default=1, metavar="N",
                   help="parallel worker processes (default: 1); the tables are the same "
                        "as with one")
    b.add_argument("--force", action="store_true",
                   help="redo every spectrum, even where a newer table exists")
    b.add_argument("--reflectances", metavar="SET", default="white",
                   help="the surface colours every table is optimized for (design §4.5): "
                        "'white' (one white surface, design §4.1; default), 'colorchecker' "
                        "(the 24 patches colour-science ships) or a CSV file (design §3.4: a "
                        "wavelength column, then one column per reflectance). A kept table "
                        "made for other colours is optimized again")
    solver_args(b, names)
    range_args(b)
    b.set_defaults(func=cmd_batch)
