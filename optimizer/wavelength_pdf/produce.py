"""From a spectrum to a written, self-describing table: the library side of ``optimize``.

The command line (:mod:`wavelength_pdf.cli`) and the evaluation
(:mod:`wavelength_pdf.evaluation.protocol`) both use :func:`optimize_one`: optimize, judge the
result's health, write the table with a ``key: value`` comment header (:func:`header_lines`,
read back by :func:`read_header`) only when it is accepted, and draw the optional images.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from wavelength_pdf import __version__
from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.table import Table, write_table


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
        if (lo, hi) != (380.0, 780.0):
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
    m = int(round(n))
    if m < 1 or abs(n - m) > 1e-9 * max(1.0, n):
        raise GridError(f"--grid-step {step:g} nm does not divide the range {lo:g}-{hi:g} nm")
    return np.linspace(lo, hi, m + 1)


def field_of(obj: Any, name: str, default: Any = None) -> Any:
    """Attribute or mapping key ``name`` of ``obj``."""
    if isinstance(obj, dict):
        return obj.get(name, default)
    return getattr(obj, name, default)


def format_value(x: Any) -> str:
    """A number for headers and summaries: full precision for floats, else str()."""
    if isinstance(x, (float, np.floating)):
        return repr(float(x))
    if isinstance(x, (np.ndarray, list, tuple)):
        return "[" + ", ".join(format_value(v) for v in np.asarray(x, dtype=float).ravel()) + "]"
    return str(x)


def health_fields(health: Any, reference: Any = None) -> dict[str, Any]:
    """bias_rel, std_rel (3,), accepted and reason of a health report.

    Reads :class:`wavelength_pdf.health.Health` (``bias``, ``std``, and ``accepted`` /
    ``reason`` methods judged against the initialization's health ``reference``) as well
    as plain records with ``bias_rel``, ``std_rel``, ``accepted`` and ``reason`` values.
    """
    if health is None:
        return {}

    def value(*names: str) -> Any:
        for n in names:
            v = field_of(health, n)
            if v is not None:
                return v(reference) if callable(v) else v
        return None

    std = value("std_rel", "std")
    reason = value("reason")
    return {
        "bias_rel": value("bias_rel", "bias"),
        "std_rel": None if std is None else np.asarray(std, dtype=float).reshape(-1),
        "accepted": bool(value("accepted")),
        "reason": reason or "",
    }


def result_health(result: Any) -> dict[str, Any]:
    """:func:`health_fields` of a result's table, judged against its initialization."""
    return health_fields(field_of(result, "health"), field_of(result, "health_init"))


def result_table(result: Any, grid: np.ndarray) -> Table:
    """The optimized table of a result (a :class:`Table`, or the (4, M+1) densities)."""
    t = field_of(result, "table")
    if isinstance(t, Table):
        return t
    return Table(grid=np.asarray(grid, dtype=float), pdfs=np.asarray(t, dtype=float))


def header_lines(spectrum: Spectrum, result: Any, seed: int | None) -> list[str]:
    """Comment header of a written table: ``key: value`` lines (``show`` reads them back)."""
    h = result_health(result)
    hi = health_fields(field_of(result, "health_init"))
    ju, jr = field_of(result, "J_uniform"), field_of(result, "J")
    lines = [
        f"wavelength-pdf {__version__}: four wavelength densities (SPEC 2; "
        f"piecewise linear, balance heuristic)",
        f"name: {spectrum.name}",
        f"source: {spectrum.source}",
        "objective: J = mean over u of CIEDE2000(C(u), c) (SPEC 4); J_fine: the same with a "
        "finer u quadrature; J_uniform: stratified uniform sampling; J_init: equal-mass "
        "initialization",
        f"J_uniform: {format_value(ju)}",
        f"J_init: {format_value(field_of(result, 'J_init'))}",
        f"J: {format_value(jr)}",
        f"J_fine: {format_value(field_of(result, 'J_fine'))}",
    ]
    if isinstance(ju, (float, int, np.floating)) and ju and jr is not None:
        lines.append(f"J_over_uniform: {format_value(float(jr) / float(ju))}")
    if h:
        lines += [f"bias_rel: {format_value(h['bias_rel'])}",
                  f"std_rel: {format_value(h['std_rel'])}",
                  f"accepted: {h['accepted']}"]
    if hi:
        lines += [f"init_bias_rel: {format_value(hi['bias_rel'])}",
                  f"init_std_rel: {format_value(hi['std_rel'])}"]
    lines += [f"solver: {field_of(result, 'solver')}",
              f"seed: {seed}",
              f"seconds: {format_value(field_of(result, 'seconds'))}",
              f"message: {field_of(result, 'message', '')}",
              f"version: {__version__}"]
    return lines


def safe_name(name: str) -> str:
    """``name`` made safe as a file name (runs of other characters become '_')."""
    return re.sub(r"[^\w.+-]+", "_", name).strip("_") or "table"


def read_header(table: Table) -> dict[str, str]:
    """``key: value`` comment lines of a table written by :func:`header_lines`."""
    out: dict[str, str] = {}
    for c in table.comments:
        key, sep, value = c.partition(":")
        if sep and re.fullmatch(r"[A-Za-z_]\w*", key.strip()):
            out.setdefault(key.strip(), value.strip())
    return out


def summary_line(spectrum: Spectrum, result: Any, out: Path | None) -> str:
    """One line: name, J result vs uniform and init, health, solver, time, output."""
    h = result_health(result)
    ju, ji, jr = (field_of(result, k) for k in ("J_uniform", "J_init", "J"))
    ratio = f" = {float(jr) / float(ju):.4f} x uniform" if ju else ""
    std = h.get("std_rel")
    std_s = "/".join(f"{v:.3g}" for v in std) if std is not None else "?"
    bias = h.get("bias_rel")
    state = "accepted" if h.get("accepted") else f"NOT accepted ({h.get('reason') or field_of(result, 'message', '')})"
    dest = f" -> {out}" if out is not None else ""
    return (f"{spectrum.name}: J {float(jr):.5g} (uniform {float(ju):.5g}, init {float(ji):.5g})"
            f"{ratio}; bias {float(bias) if bias is not None else float('nan'):.2g}, "
            f"std/c {std_s}; {state}; {field_of(result, 'solver')} "
            f"{float(field_of(result, 'seconds', 0.0)):.1f} s{dest}")


@dataclass
class Outcome:
    """What :func:`optimize_one` did for one spectrum."""

    spectrum: Spectrum
    result: Any
    path: Path
    written: bool


def optimize_one(spectrum: Spectrum, path: Path, grid: np.ndarray, solver: str | None,
                 seed: int, max_seconds: float | None, progress: Callable | None,
                 colour_bar: Path | None = None, plot: Path | None = None) -> Outcome:
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
    result = optimize_spectrum(spectrum, **kwargs)
    table = result_table(result, grid)
    accepted = bool(result_health(result).get("accepted")) and \
        bool(field_of(result, "accepted", True))
    if accepted:
        table = Table(grid=table.grid, pdfs=table.pdfs,
                      comments=header_lines(spectrum, result, seed))
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
    return Outcome(spectrum, result, path, accepted)
