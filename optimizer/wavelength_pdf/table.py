"""The wavelength-table file (design §2): one reader, one writer.

A table holds N = 4 densities over one strictly increasing grid of nodes (nm). Each density
is piecewise linear between nodes and integrates to 1 by the trapezoid rule (design §1).

Two layouts are read:

- the commented CSV that :func:`write_table` writes::

      # comment lines start with '#'
      lambda_nm,pdf0,pdf1,pdf2,pdf3
      380,0.00112,0,0,0
      ...

- the headerless "4 x 81" layout in which Dobos 2025 distributed its tables: four rows of 81 comma-separated densities
  at 380, 385, ..., 780 nm (a trailing comma on a row is allowed).

Readers renormalize each density and reject, naming file, line and reason: a NaN, an
infinity, a negative value, a density zero everywhere, a grid not strictly increasing, a
column count other than 5, fewer than 2 nodes, a missing file.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Table", "TableError", "read_table", "write_table", "normalize", "N_DENSITIES",
           "HEADER", "GRID_4X81"]

from wavelength_pdf.model import N_DENSITIES, RANGE, trapezoid

#: Column header of the CSV layout (design §2).
HEADER = "lambda_nm,pdf0,pdf1,pdf2,pdf3"
#: Grid of the headerless 4 x 81 layout: 380..780 nm in 5 nm steps (design §2).
GRID_4X81 = np.linspace(RANGE[0], RANGE[1], 81)


class TableError(ValueError):
    """A table file that cannot be used; the message reads ``path:line: reason``."""


@dataclass
class Table:
    """Four piecewise-linear wavelength densities on one grid.

    Attributes
    ----------
    grid : np.ndarray
        Nodes, nm, strictly increasing, shape (M+1,), M+1 >= 2.
    pdfs : np.ndarray
        Density values at the nodes, 1/nm, shape (4, M+1), each >= 0 and integrating to 1
        by the trapezoid rule.
    comments : list of str
        Header comment lines, without the leading '#'.
    """

    grid: np.ndarray
    pdfs: np.ndarray
    comments: list[str] = field(default_factory=list)


_trapezoid = trapezoid


def normalize(grid: np.ndarray, pdfs: np.ndarray) -> np.ndarray:
    """Scale each row of ``pdfs`` so it integrates to 1 over ``grid`` (trapezoid rule).

    Rows already normalized to within rounding (1e-13) are kept as they are, so a table that
    was written normalized reads back bit for bit.
    """
    mass = _trapezoid(grid, pdfs)
    scale = np.where(np.abs(mass - 1.0) <= 1e-13, 1.0, mass)
    return pdfs / scale[:, None]


def _validate(path: Path, grid: np.ndarray, pdfs: np.ndarray,
              grid_lines: list[int], value_line) -> Table:
    """Check a parsed table; ``value_line(k, i)`` gives the file line of pdfs[k, i]."""
    if grid.size < 2:
        line = grid_lines[0] if grid_lines else 1
        raise TableError(f"{path}:{line}: a table needs at least 2 grid nodes, got {grid.size}")
    for i in range(grid.size):
        if not np.isfinite(grid[i]):
            raise TableError(f"{path}:{grid_lines[i]}: wavelength is {grid[i]} (must be finite)")
    for k in range(pdfs.shape[0]):
        for i in range(pdfs.shape[1]):
            v = pdfs[k, i]
            if np.isnan(v):
                raise TableError(f"{path}:{value_line(k, i)}: pdf{k} is NaN at {grid[i]:g} nm")
            if np.isinf(v):
                raise TableError(f"{path}:{value_line(k, i)}: pdf{k} is infinite at {grid[i]:g} nm")
            if v < 0:
                raise TableError(f"{path}:{value_line(k, i)}: pdf{k} is negative ({float(v)!r}) "
                                 f"at {grid[i]:g} nm")
    bad = np.flatnonzero(np.diff(grid) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise TableError(f"{path}:{grid_lines[i]}: grid is not strictly increasing "
                         f"({float(grid[i - 1])!r} then {float(grid[i])!r} nm)")
    mass = _trapezoid(grid, pdfs)
    for k in range(pdfs.shape[0]):
        if not mass[k] > 0:
            raise TableError(f"{path}:{value_line(k, 0)}: pdf{k} is zero everywhere")
        if not np.isfinite(mass[k]):
            raise TableError(f"{path}:{value_line(k, 0)}: pdf{k} integrates to {mass[k]} "
                             f"(values too large)")
    return Table(grid=grid, pdfs=normalize(grid, pdfs))


def _number(token: str, where: str) -> float:
    try:
        return float(token)
    except ValueError:
        raise TableError(f"{where}: cannot parse number {token!r}") from None


def read_table(path: str | os.PathLike) -> Table:
    """Read a wavelength table in either layout of design §2 and renormalize its densities.

    Parameters
    ----------
    path : path-like
        The table file.

    Returns
    -------
    Table
        Grid (nm), four densities (1/nm) each integrating to 1, and the comment lines.

    Raises
    ------
    TableError
        Missing file or malformed content; the message names file, line and reason.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig", errors="replace")
    except FileNotFoundError:
        raise TableError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise TableError(f"{path}: is a directory, not a table file") from None
    except OSError as e:
        raise TableError(f"{path}: cannot read ({e.strerror})") from None

    comments: list[str] = []
    rows: list[tuple[int, list[str]]] = []
    header_line = 0
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            comments.append(line[1:].strip())
            continue
        fields = [f.strip() for f in line.split(",")]
        if len(fields) > 1 and fields[-1] == "":
            fields.pop()  # a trailing comma (the 4 x 81 files of Dobos 2025 have some)
        if not rows and not header_line and fields and fields[0].lower().startswith("lambda"):
            header_line = lineno
            if len(fields) != 1 + N_DENSITIES:
                raise TableError(f"{path}:{lineno}: header has {len(fields)} columns, "
                                 f"expected {1 + N_DENSITIES} ({HEADER})")
            continue
        rows.append((lineno, fields))

    if not rows:
        raise TableError(f"{path}:{header_line or max(1, len(text.splitlines()))}: "
                         f"no data rows (a table needs at least 2 grid nodes)")

    # The 4 x 81 layout: no header, four rows of (many) densities on 380..780 nm.
    if not header_line and all(len(f) > 1 + N_DENSITIES for _, f in rows):
        if len(rows) != N_DENSITIES:
            raise TableError(f"{path}:{rows[min(len(rows), N_DENSITIES) - 1][0]}: "
                             f"{len(rows)} rows of densities, expected {N_DENSITIES} "
                             f"(headerless 4 x 81 layout)")
        for lineno, f in rows:
            if len(f) != GRID_4X81.size:
                raise TableError(f"{path}:{lineno}: {len(f)} densities, expected "
                                 f"{GRID_4X81.size} (headerless 4 x 81 layout, 380..780 nm)")
        pdfs = np.array([[_number(v, f"{path}:{lineno}") for v in f] for lineno, f in rows])
        grid = GRID_4X81.copy()
        lines = [lineno for lineno, _ in rows]
        table = _validate(path, grid, pdfs, [lines[0]] * grid.size, lambda k, i: lines[k])
        table.comments = comments
        return table

    # The column layout: lambda, pdf0..pdf3 per row.
    for lineno, f in rows:
        if len(f) != 1 + N_DENSITIES:
            raise TableError(f"{path}:{lineno}: {len(f)} columns, expected {1 + N_DENSITIES} "
                             f"({HEADER})")
    data = np.array([[_number(v, f"{path}:{lineno}") for v in f] for lineno, f in rows])
    lines = [lineno for lineno, _ in rows]
    table = _validate(path, data[:, 0].copy(), data[:, 1:].T.copy(), lines,
                      lambda k, i: lines[i])
    table.comments = comments
    return table


def format_table(table: Table) -> str:
    """The text of ``table`` in the commented CSV layout (repr-precision numbers)."""
    grid = np.asarray(table.grid, dtype=np.float64)
    pdfs = np.asarray(table.pdfs, dtype=np.float64)
    if pdfs.shape != (N_DENSITIES, grid.size):
        raise TableError(f"table to write has pdfs of shape {pdfs.shape}, "
                         f"expected ({N_DENSITIES}, {grid.size})")
    out: list[str] = []
    for c in table.comments:
        for part in str(c).splitlines() or [""]:
            out.append(f"# {part}".rstrip())
    out.append(HEADER)
    for i in range(grid.size):
        # repr of a Python float is the shortest string that reads back to the same double.
        out.append(",".join(repr(float(v)) for v in (grid[i], *pdfs[:, i])))
    return "\n".join(out) + "\n"


def write_table(path: str | os.PathLike, table: Table) -> None:
    """Write ``table`` in the commented CSV layout, atomically.

    The table is validated first (same rules as :func:`read_table`), written to a temporary
    file beside ``path`` and renamed over it, so an error never leaves a partial or wrong
    file. Numbers are written at full (repr) precision: reading back gives the same doubles.

    Raises
    ------
    TableError
        The table is malformed (the message names the 1-based grid row of the problem).
    """
    path = Path(path)
    text = format_table(table)
    # Validate exactly what will be read back (this also rejects NaN, negatives, ...).
    grid = np.asarray(table.grid, dtype=np.float64)
    where = Path(f"{path} (not written)")
    _validate(where, grid, np.asarray(table.pdfs, dtype=np.float64),
              [i + 1 for i in range(grid.size)], lambda k, i: i + 1)
    directory = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; a table is an ordinary file
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
