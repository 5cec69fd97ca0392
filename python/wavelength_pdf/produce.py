"""From a spectrum to a written, self-describing table: the library side of ``optimize``.

The command line (:mod:`wavelength_pdf.cli`) and the evaluation
(:mod:`wavelength_pdf.evaluation.protocol`) both use :func:`optimize_one`: optimize, judge the
result's health, write the table with its record as a ``key: value`` comment header
(:meth:`Result.header_lines`, read back by :meth:`Result.from_table`) only when it is
accepted, and draw the optional images.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.model import RANGE, check_table_nodes
from wavelength_pdf.result import Result, read_header  # noqa: F401  (read_header: re-export)
from wavelength_pdf.table import write_table


class OutputPathError(ValueError):
    """An output file that cannot be written; the message reads ``PATH: reason``."""


def check_output_path(path: Path) -> None:
    """Fail now, not after a long optimization, when ``path`` cannot be written.

    The file must have a name, must not be a directory, and its directory (created later if
    missing) must be one where a file can be created: the check creates and removes a
    temporary file there, since permission bits do not tell (root, /proc, read-only mounts).

    Raises
    ------
    OutputPathError
        Naming the path and the reason.
    """
    import os
    import tempfile

    p = Path(path)
    if str(path) == "" or p.name == "":
        raise OutputPathError(f"{str(path)!r}: empty output file name")
    if p.is_dir():
        raise OutputPathError(f"{p}: is a directory, not a file name")
    ancestor = p.parent if str(p.parent) else Path(".")
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise OutputPathError(f"{p}: {ancestor} is not a directory")
    # The directory, or the nearest existing one above it where the missing ones will go.
    try:
        fd, probe = tempfile.mkstemp(dir=ancestor, prefix=".wavelength-pdf-probe-")
    except OSError as e:
        raise OutputPathError(f"{p}: cannot create a file in {ancestor} ({e.strerror})") from None
    os.close(fd)
    os.unlink(probe)


class GridError(ValueError):
    """A table grid that cannot be built from the given range and step."""


def make_grid(lo: float, hi: float, step: float | str) -> np.ndarray | str:
    """Table grid ``lo, lo+step, ..., hi`` (nm); ``hi - lo`` must be a multiple of ``step``.

    ``step == "auto"`` returns "auto": the optimizer's own grid (5 nm, refined around
    emission lines; :mod:`wavelength_pdf.grids`), available on the default range only."""
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise GridError(f"--range must be two finite wavelengths LO < HI, got {lo:g} {hi:g}")
    if step == "auto":
        if (lo, hi) != RANGE:
            raise GridError("--grid-step auto works on the default range 380-780 nm only; "
                           "give a step in nm for another range")
        return "auto"
    try:
        step = float(step)
    except ValueError:
        raise GridError(f"--grid-step must be a number of nm or 'auto', got {step!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise GridError(f"--range must be two finite wavelengths LO < HI, got {lo:g} {hi:g}")
    if not (math.isfinite(step) and step > 0):
        raise GridError(f"--grid-step must be positive, got {step:g}")
    n = (hi - lo) / step
    # Before the grid is made: a step of 1e-9 nm would ask for 4e11 nodes.
    check_table_nodes(n + 1, f"--grid-step {step:g} nm over {lo:g}-{hi:g} nm")
    m = int(round(n))
    if m < 1 or abs(n - m) > 1e-9 * max(1.0, n):
        raise GridError(f"--grid-step {step:g} nm does not divide the range {lo:g}-{hi:g} nm")
    return np.linspace(lo, hi, m + 1)


def safe_name(name: str) -> str:
    """``name`` made safe as a file name (runs of other characters become '_')."""
    return re.sub(r"[^\w.+-]+", "_", name).strip("_") or "table"


def summary_line(result: Result, out: Path | None) -> str:
    """One line: name, J result vs uniform and init, health, solver, time, output."""
    std = "/".join(f"{v:.3g}" for v in result.std_rel)
    state = "accepted" if result.accepted else f"NOT accepted ({result.reason})"
    dest = f" -> {out}" if out is not None else ""
    return (f"{result.name}: J {result.J:.5g} (uniform {result.J_uniform:.5g}, init "
            f"{result.J_init:.5g}) = {result.J_over_uniform:.4f} x uniform; bias "
            f"{result.bias_rel:.2g}, std/c {std}; {state}; {result.solver} "
            f"{result.seconds:.1f} s{dest}")


@dataclass
class Outcome:
    """What :func:`optimize_one` did for one spectrum."""

    spectrum: Spectrum
    result: Result
    path: Path
    written: bool


def optimize_one(spectrum: Spectrum, path: Path, grid: np.ndarray | str, solver: str | None,
                 seed: int, max_seconds: float | None, progress: Callable | None,
                 colour_bar: Path | None = None, plot: Path | None = None,
                 max_evals: int | None = None, reflectances=None, objective: str = "J",
                 objective_spp: int | None = None) -> Outcome:
    """Optimize one spectrum; write its table (only if accepted) and the optional images.

    Every output path is checked first (:func:`check_output_path`), before the optimization.
    """
    from wavelength_pdf.optimize import optimize_spectrum

    for out in (path, colour_bar, plot):
        if out is not None:
            check_output_path(out)

    kwargs: dict[str, Any] = {"grid": grid, "seed": seed, "progress": progress,
                              "max_seconds": max_seconds}
    if solver is not None:
        kwargs["solver"] = solver
    if max_evals is not None:
        kwargs["solver_options"] = {"max_evals": int(max_evals)}
    if reflectances is not None:
        kwargs["reflectances"] = reflectances
    if objective != "J":
        kwargs["objective"] = objective
        if objective_spp is not None:
            kwargs["objective_spp"] = objective_spp
    result = optimize_spectrum(spectrum, **kwargs)
    table = result.to_table()
    if result.accepted:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_table(path, table)
    if colour_bar is not None or plot is not None:
        from wavelength_pdf import plots

        if colour_bar is not None:
            colour_bar.parent.mkdir(parents=True, exist_ok=True)
            plots.colour_bar_png(colour_bar, spectrum, table)
        if plot is not None:
            plot.parent.mkdir(parents=True, exist_ok=True)
            plots.densities_png(plot, spectrum, table)
    return Outcome(spectrum, result, path, result.accepted)
