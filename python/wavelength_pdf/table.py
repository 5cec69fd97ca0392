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
column count other than 5, fewer than 2 nodes, a missing file, a file that is not a regular
file or is larger than 64 MiB, a control character.

What a line, a field and a number are is the same in every reader of tables (design §2; the
C++ header ``wavelength_table.h`` follows the same rules, and both are tested on the files of
``tests/data/tables/edge``): a line ends at LF, CR LF or a lone CR and nothing else; any other
control character is an error; fields are separated by commas and trimmed of spaces and tabs;
a number is written in ASCII (``float()`` alone would also take Unicode digits and ``1_000``).
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Table", "TableError", "read_table", "write_table", "normalize", "N_DENSITIES",
           "HEADER", "GRID_4X81"]

from wavelength_pdf.files import MAX_INPUT_BYTES, read_input_text
from wavelength_pdf.model import N_DENSITIES, RANGE, normalize_density, trapezoid

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

#: A density whose largest value lies outside [2^-64, 2^64] is scaled by a power of two to a
#: largest value in [0.5, 1) before it is integrated (design §2.3): exact, and it keeps the
#: trapezoid sums out of the subnormal numbers (densities of 5e-324 each once summed to a
#: mass 16 % off) and away from overflow. Other densities are integrated as they are, so a
#: table written normalized reads back bit for bit. The same bounds as for spectra (§3.3).
PEAK_RANGE: tuple[float, float] = (2.0**-64, 2.0**64)

#: The smallest mass a density may have once scaled: with every value 0 or at least 2^-1022,
#: areas that underflow change a mass this large by less than 1e-100 of it (only a grid
#: narrower than ~1e-250 nm gets below it).
_MIN_MASS = 2.0**-900

_SIGN = np.uint64(1 << 63)
_MAGNITUDE = np.uint64((1 << 63) - 1)
_FRACTION = np.uint64((1 << 52) - 1)


def _bits(values: np.ndarray) -> np.ndarray:
    """The IEEE 754 bits of float64 ``values`` as uint64."""
    return np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)


def _order_key(values: np.ndarray) -> np.ndarray:
    """Integers in the order of the finite ``values`` (+0 and -0 equal, subnormals included),
    taken from their bits: in a thread that treats subnormal numbers as zero (Dr.Jit's, where
    the Mitsuba plugin reads its table) comparing the floats themselves gives other answers."""
    b = _bits(values)
    mag = (b & _MAGNITUDE).astype(np.int64)
    return np.where((b & _SIGN) != 0, -mag, mag)


def _exact_scaled(pdfs: np.ndarray) -> np.ndarray:
    """Each row of ``pdfs`` (finite, >= 0) scaled by a power of two to a peak in [0.5, 1) when
    its peak lies outside ``PEAK_RANGE``, with every value that is then below 2^-1022 (a
    subnormal number, below 2^-958 of the peak) read as 0 (design §2.3).

    Done on the numbers' bits, with integers only: exact, and the same in a thread that
    flushes subnormal numbers to zero (Dr.Jit's) as elsewhere, where float arithmetic on
    them is not (such a thread once read a table of 5e-324 as "zero everywhere"). The C++
    reader (``wavelength_table.h``) does the same.
    """
    pdfs = np.array(pdfs, dtype=np.float64, ndmin=2)
    out = np.zeros_like(pdfs)
    for k in range(pdfs.shape[0]):
        b = _bits(pdfs[k]) & _MAGNITUDE
        if not b.any():
            continue
        biased = (b >> np.uint64(52)).astype(np.int64)
        frac = (b & _FRACTION).astype(np.int64)
        # value = sig * 2^e exactly, sig < 2^53; bit_length(sig) via frexp of a whole number
        sig = np.where(biased > 0, frac | (1 << 52), frac)
        e = np.where(biased > 0, biased - 1075, -1074)
        length = np.frexp(sig.astype(np.float64))[1]
        top = e + length - 1  # value in [2^top, 2^(top + 1))
        i = int(np.argmax(b))  # the peak: the bits of non-negative doubles are in their order
        power_of_two = sig[i] == 1 << (length[i] - 1)
        inside = -64 <= top[i] < 64 or (top[i] == 64 and power_of_two)
        shift = 0 if inside else -(int(top[i]) + 1)
        top = top + shift
        normal = (sig > 0) & (top >= -1022)
        mantissa = np.left_shift(sig, np.maximum(53 - length, 0)) & ((1 << 52) - 1)
        bits = ((top + 1023).astype(np.uint64) << np.uint64(52)) | mantissa.astype(np.uint64)
        out[k] = np.where(normal, bits, np.uint64(0)).view(np.float64)
    return out


def normalize(grid: np.ndarray, pdfs: np.ndarray) -> np.ndarray:
    """Scale each row of ``pdfs`` so it integrates to 1 over ``grid`` (trapezoid rule).

    Rows with a peak outside ``PEAK_RANGE`` are first scaled by a power of two (design
    §2.3), so that the mass is exact to rounding whatever the values' magnitude. Rows
    already normalized to within rounding (1e-13) are kept as they are, so a table that was
    written normalized reads back bit for bit.
    """
    return normalize_density(grid, _exact_scaled(pdfs), keep_within=1e-13)


def _format_number(v: float) -> str:
    """The shortest ``%g`` text (6 to 17 digits) that reads back as ``v``: how both table
    readers write a number in a message (the header's ``detail::FormatNumber``), so that they
    report "390 then 390 nm" alike where ``repr`` would write "390.0"."""
    v = float(v)
    for digits in range(6, 17):
        text = f"{v:.{digits}g}"
        if float(text) == v:
            return text
    return f"{v:.17g}"


def _validate(path: Path, grid: np.ndarray, pdfs: np.ndarray,
              grid_lines: list[int], value_line) -> Table:
    """Check a parsed table; ``value_line(k, i)`` gives the file line of pdfs[k, i]."""
    if grid.size < 2:
        line = grid_lines[0] if grid_lines else 1
        raise TableError(f"{path}:{line}: a table needs at least 2 grid nodes, got {grid.size}")
    for i in range(grid.size):
        if not np.isfinite(grid[i]):
            raise TableError(f"{path}:{grid_lines[i]}: wavelength is {_format_number(grid[i])} "
                             "(must be finite)")
    for k in range(pdfs.shape[0]):
        for i in range(pdfs.shape[1]):
            v = pdfs[k, i]
            if np.isnan(v):
                raise TableError(f"{path}:{value_line(k, i)}: pdf{k} is NaN at {grid[i]:g} nm")
            if np.isinf(v):
                raise TableError(f"{path}:{value_line(k, i)}: pdf{k} is infinite at {grid[i]:g} nm")
            if np.signbit(v) and _bits(np.array([v]))[0] & _MAGNITUDE:  # -0 is 0
                raise TableError(f"{path}:{value_line(k, i)}: pdf{k} is negative ({_format_number(v)}) "
                                 f"at {grid[i]:g} nm")
    key = _order_key(grid)
    bad = np.flatnonzero(key[1:] <= key[:-1])
    if bad.size:
        i = int(bad[0]) + 1
        raise TableError(f"{path}:{grid_lines[i]}: grid is not strictly increasing "
                         f"({_format_number(grid[i - 1])} then {_format_number(grid[i])} nm)")
    # Integrate each density with its peak brought into [2^-64, 2^64] and no subnormal value
    # left (exact, _exact_scaled), then divide: the renormalization is exact to rounding, or
    # the table is refused (design §2.3).
    scaled = _exact_scaled(pdfs)
    with np.errstate(over="ignore", invalid="ignore"):  # a grid wider than the doubles
        mass = _trapezoid(grid, scaled)
    for k in range(pdfs.shape[0]):
        if not _bits(scaled[k]).any():
            raise TableError(f"{path}:{value_line(k, 0)}: pdf{k} is zero everywhere")
        if not np.isfinite(mass[k]):
            raise TableError(f"{path}:{value_line(k, 0)}: pdf{k} integrates to infinity "
                             "(the grid is too wide)")
        if not mass[k] >= _MIN_MASS:  # then no value / mass overflows either (< 2^965)
            raise TableError(f"{path}:{value_line(k, 0)}: pdf{k} cannot be normalized "
                             "exactly (the grid is too narrow)")
    return Table(grid=grid, pdfs=normalize(grid, pdfs))


#: A number in a table (design §2): ASCII digits with an optional sign, point and exponent,
#: or nan / inf / infinity in any case. float() alone would also read Unicode digits,
#: underscores (1_000) and surrounding Unicode white space, which the C++ reader does not.
_NUMBER = re.compile(r"[+-]?(?:(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                     r"|nan|inf|infinity)", re.IGNORECASE | re.ASCII)

#: Where a line ends (design §2): LF, CR LF or a lone CR; nothing else.
_LINE_END = re.compile(r"\r\n|\r|\n")

#: Control characters other than tab (C0, DEL and C1, NEL included): an error anywhere in a
#: table (design §2). CR and LF never get here: they end lines.
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")

#: What fields are trimmed of (design §2): spaces and tabs, not Unicode white space.
_BLANK = " \t"


def _lines(text: str) -> list[str]:
    """The lines of ``text`` as design §2 defines them (a last line end starts no line)."""
    lines = _LINE_END.split(text)
    if lines and lines[-1] == "":
        lines.pop()
    return lines


#: Below this magnitude float() may round differently in a thread that flushes subnormal
#: results to zero (Dr.Jit's, where the Mitsuba plugin reads its table: "5e-324" gave 0).
_SUBNORMAL_SPACING_ENDS = 2.0**-1021


def _number(token: str, where: str) -> float:
    if not _NUMBER.fullmatch(token):
        raise TableError(f"{where}: cannot parse number {token!r}")
    v = float(token)
    if abs(v) < _SUBNORMAL_SPACING_ENDS:  # False for NaN and infinities
        v = _exact_tiny(token, v)
    return v


def _exact_tiny(token: str, v: float) -> float:
    """``token`` (a decimal below 2^-1021 in magnitude) rounded to the nearest double with
    integers only: on [0, 2^-1021) the doubles are the multiples of 2^-1074, so the bits of
    the magnitude are round(|x| 2^1074) (ties to even), whatever the FPU's mode."""
    from fractions import Fraction

    x = Fraction(token)
    if x == 0:
        return v  # 0.0 or -0.0, as written
    n = round(abs(x) * (1 << 1074))  # Fraction rounds half to even
    if n >= 1 << 53:  # not below 2^-1021 after all (v was flushed or rounded): float() is right
        return v
    bits = n | (1 << 63 if x < 0 else 0)
    return float(np.array([bits], dtype=np.uint64).view(np.float64)[0])


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
        Missing file, not a regular file, larger than 64 MiB, or malformed content; the
        message names file, line and reason.
    """
    path = Path(path)
    text = read_input_text(path, "table", TableError, MAX_INPUT_BYTES)
    text_lines = _lines(text)

    comments: list[str] = []
    rows: list[tuple[int, list[str]]] = []
    header_line = 0
    for lineno, raw in enumerate(text_lines, start=1):
        bad = _CONTROL.search(raw)
        if bad:
            raise TableError(f"{path}:{lineno}: control character U+{ord(bad.group()):04X} is "
                             "not allowed in a table (design §2)")
        line = raw.strip(_BLANK)
        if not line:
            continue
        if line.startswith("#"):
            comments.append(line[1:].strip(_BLANK))
            continue
        fields = [f.strip(_BLANK) for f in line.split(",")]
        if len(fields) > 1 and fields[-1] == "":
            fields.pop()  # a trailing comma (the 4 x 81 files of Dobos 2025 have some)
        first = fields[0][:6]
        if not rows and not header_line and first.isascii() and first.lower() == "lambda":
            header_line = lineno
            if len(fields) != 1 + N_DENSITIES:
                raise TableError(f"{path}:{lineno}: header has {len(fields)} columns, "
                                 f"expected {1 + N_DENSITIES} ({HEADER})")
            continue
        rows.append((lineno, fields))

    if not rows:
        raise TableError(f"{path}:{header_line or max(1, len(text_lines))}: "
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
        # One comment line per line of the text; control characters, which a reader refuses
        # (design §2), become spaces.
        for part in str(c).splitlines() or [""]:
            out.append(f"# {_CONTROL.sub(' ', part)}".rstrip())
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
