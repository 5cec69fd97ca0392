"""``wavelength-pdf show``: a table's grid, normalization, header and, for a spectrum, J."""
from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

from wavelength_pdf.cli import PROG, SPECTRUM_HELP, BadInput, Formatter, objective_args, objective_options
from wavelength_pdf.coverage import coverage
from wavelength_pdf.model import trapezoid
from wavelength_pdf.spectra import load_spectra
from wavelength_pdf.table import read_table


def cmd_show(args: argparse.Namespace) -> int:
    objective, spp = objective_args(args)
    if objective != "J" and not args.spectrum:
        raise BadInput("--objective needs --spectrum (the table is scored for a spectrum)")
    table = read_table(args.table)
    grid, pdfs = table.grid, table.pdfs
    steps = np.diff(grid)
    uniform = np.allclose(steps, steps[0], rtol=1e-9, atol=0)
    print(f"table: {args.table}")
    for c in table.comments:
        print(f"  # {c}")
    print(f"grid: {grid.size} nodes, {grid[0]:g}-{grid[-1]:g} nm, "
          + (f"step {steps[0]:g} nm" if uniform else
             f"irregular steps {steps.min():g}-{steps.max():g} nm"))
    mass = trapezoid(grid, pdfs)
    for k in range(pdfs.shape[0]):
        nz = np.flatnonzero(pdfs[k] > 0)
        print(f"pdf{k}: integral {mass[k]:.15g}, max {pdfs[k].max():.6g} /nm at "
              f"{grid[int(np.argmax(pdfs[k]))]:g} nm, non-zero {grid[nz[0]]:g}-{grid[nz[-1]]:g} nm")
    mix = pdfs.mean(axis=0)
    zero = grid[mix <= 0]
    print(f"mixture: min {mix.min():.6g} /nm" +
          (f", ZERO at {zero.size} nodes ({zero[0]:g}-{zero[-1]:g} nm)" if zero.size else
           ", positive at every node"))
    if args.spectrum:
        lo, hi = float(grid[0]), float(grid[-1])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            spectra = load_spectra(args.spectrum, lo=lo, hi=hi)
        from wavelength_pdf.optimize import evaluate_table

        for sp in spectra:
            # Light the table never samples (design §1.5), as the renderer warns about it.
            for w in coverage(grid, pdfs, sp).warnings(sp.name):
                print(f"{PROG}: warning: {w}", file=sys.stderr)
            ev = evaluate_table(sp, table, objective=objective, objective_spp=spp)
            named = "" if objective == "J" else f" [{ev.objective}]"
            print(f"{sp.name}: J{named} {ev.J:.6g} (J_fine {ev.J_fine:.6g}), uniform "
                  f"{ev.J_uniform:.6g}, ratio {ev.J_over_uniform:.4f}")
            print(f"  health: bias_rel {ev.bias_rel:.3g}, std/c "
                  f"{'/'.join(f'{v:.4g}' for v in ev.std_rel)}, "
                  f"{'accepted' if ev.accepted else 'NOT accepted: ' + ev.reason}")
    return 0


def add_parser(sub) -> None:
    s = sub.add_parser("show", formatter_class=Formatter,
                       help="print a table's grid, normalization, J and health",
                       description="Print a table's grid, the normalization of its four "
                                   "densities and its header; with --spectrum, its "
                                   "objective J and estimator health for that spectrum, and a "
                                   "warning where the table never samples light the spectrum "
                                   "emits (design §1.5).")
    s.add_argument("table", metavar="TABLE", help="table file (either layout of design §2)")
    s.add_argument("--spectrum", metavar="SPECTRUM",
                   help="evaluate J and health of the table for this spectrum (" +
                        SPECTRUM_HELP + ")")
    objective_options(s, "with --spectrum, the objective J stands for")
    s.set_defaults(func=cmd_show)
