"""Lamp spectra: one type, and readers for every form users have them in (design §3).

A :class:`Spectrum` is a piecewise-linear function of wavelength, kept at the resolution it
was measured at (never resampled to a table grid) and zero outside its samples.

Spectra are named by a *spec* string (design §7):

- ``cie:NAME``  -- a standard illuminant that colour-science ships (``colour.SDS_ILLUMINANTS``:
  A, D65, FL1-FL12, HP1-HP5, LED-B1, ...);
- ``lamp:NAME`` -- a light source that colour-science ships (``colour.SDS_LIGHT_SOURCES``);
- ``*.pbrt``    -- the emitter spectra a pbrt-v4 scene uses, one per distinct emitter
  (``scene.pbrt#N`` or ``scene.pbrt#NAME`` picks one, see :mod:`wavelength_pdf.scene_spectra`);
- ``*.spd``     -- a pbrt spectrum file: ``lambda value`` pairs, whitespace separated;
- ``*.csv``     -- an LSPDD export (https://lspdd.org): ``# Key : Value`` lines, a
  ``wavelength, intensity`` header, then ``lambda,value`` rows; rows with zero intensity
  are left out of those exports, so a gap in the grid is a stretch of zeros.

Every reader rejects bad input with a :class:`SpectrumError` whose message starts with
``path:line:``.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from wavelength_pdf.files import MAX_INPUT_BYTES, read_input_text
from wavelength_pdf.model import RANGE

__all__ = [
    "Spectrum",
    "SpectrumError",
    "VISIBLE_RANGE",
    "load_spectra",
    "load_spectrum",
    "check_support",
    "make_spectrum",
    "read_spd",
    "read_lspdd_csv",
    "cie_illuminant",
    "light_source",
    "READERS",
    "register_reader",
]

#: The wavelength range of the default table grid, nm (design §1).
VISIBLE_RANGE: tuple[float, float] = RANGE


#: Spectra whose peak lies outside [2^-64, 2^64] are scaled by a power of two, exactly (every
#: ratio of values stays bit for bit), to a peak in [0.5, 1): units are arbitrary, and so
#: neither squares of the values nor the single precision of a pbrt scene written from the
#: spectrum (the evaluation's) can overflow or underflow. Other spectra keep their values.
PEAK_RANGE: tuple[float, float] = (2.0**-64, 2.0**64)

#: Values below 1/MAX_DYNAMIC_RANGE of a spectrum's peak are read as 0 (design §3.3): once the
#: peak is scaled to 1 they fall below the smallest normal double (2.2e-308), and they change
#: no integral by more than that fraction. The far tails of a Gaussian line reach the subnormal
#: numbers; refusing such a spectrum would refuse every narrow line written at fine steps.
MAX_DYNAMIC_RANGE = 1e300


class SpectrumError(ValueError):
    """A spectrum that cannot be read or used; the message reads ``path:line: reason``."""


@dataclass(frozen=True)
class Spectrum:
    """A lamp's spectral power distribution at its own resolution.

    Attributes
    ----------
    name : str
        Human-readable name (the lamp's, or the illuminant's).
    source : str
        Where it came from: ``cie:NAME``, ``lamp:NAME``, a file path, or ``scene.pbrt:LINE``.
    wavelengths : np.ndarray
        Sample wavelengths, nm, strictly increasing float64, shape (K,), K >= 2.
    values : np.ndarray
        Spectral power at the samples (arbitrary units), finite and >= 0, float64, shape (K,).
        The spectrum is linear between samples and zero outside
        ``[wavelengths[0], wavelengths[-1]]``.
    """

    name: str
    source: str
    wavelengths: np.ndarray
    values: np.ndarray

    def __call__(self, lam: np.ndarray | float) -> np.ndarray:
        """Evaluate the spectrum at wavelengths ``lam`` (nm); zero outside its samples."""
        return np.interp(lam, self.wavelengths, self.values, left=0.0, right=0.0)


def make_spectrum(
    name: str,
    source: str,
    wavelengths: np.ndarray | list[float],
    values: np.ndarray | list[float],
    where: str | None = None,
    lines: list[int] | None = None,
) -> Spectrum:
    """Validate samples and build a read-only :class:`Spectrum`.

    Parameters
    ----------
    name, source : str
        See :class:`Spectrum`.
    wavelengths, values : array_like
        Samples, nm and arbitrary units.
    where : str, optional
        File name used in error messages (defaults to ``source``).
    lines : list of int, optional
        Line number of each sample, so an error can point at the offending line.

    Raises
    ------
    SpectrumError
        Fewer than 2 samples, a non-finite or negative value, wavelengths that are not
        strictly increasing.

    A spectrum whose peak lies outside ``PEAK_RANGE`` is scaled by a power of two to a peak
    in [0.5, 1) (exact; units are arbitrary); values below ``1 / MAX_DYNAMIC_RANGE`` of the
    peak are read as 0.
    """
    where = source if where is None else where
    lam = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    val = np.asarray(values, dtype=np.float64).reshape(-1)

    def at(i: int) -> str:
        return f"{where}:{lines[i]}" if lines is not None and i < len(lines) else where

    if lam.shape != val.shape:
        raise SpectrumError(f"{where}: {lam.size} wavelengths but {val.size} values")
    if lam.size < 2:
        raise SpectrumError(
            f"{at(0) if lam.size else where}: a spectrum needs at least 2 samples, got {lam.size}"
        )
    for arr, what in ((lam, "wavelength"), (val, "value")):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise SpectrumError(f"{at(int(bad[0]))}: {what} is {arr[bad[0]]} (must be finite)")
    bad = np.flatnonzero(val < 0)
    if bad.size:
        i = int(bad[0])
        raise SpectrumError(f"{at(i)}: negative value {float(val[i])!r} at {float(lam[i])!r} nm")
    bad = np.flatnonzero(np.diff(lam) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise SpectrumError(
            f"{at(i)}: wavelengths must be strictly increasing ({float(lam[i - 1])!r} then {float(lam[i])!r} nm)"
        )
    if np.any(val > 0):
        peak = float(val.max())
        # Compared in logarithms: the ratio to the peak may not be representable.
        with np.errstate(divide="ignore"):
            negligible = (val > 0) & (np.log10(val) < math.log10(peak) - math.log10(MAX_DYNAMIC_RANGE))
        if negligible.any():
            val = np.where(negligible, 0.0, val)
        if not (PEAK_RANGE[0] <= peak <= PEAK_RANGE[1]):
            val = np.ldexp(val, -int(np.frexp(peak)[1]))  # exact: no value left underflows
    lam.setflags(write=False)
    val.setflags(write=False)
    return Spectrum(name=name, source=source, wavelengths=lam, values=val)


def _energy_inside(lam: np.ndarray, val: np.ndarray, lo: float, hi: float) -> float:
    """Integral of the piecewise-linear spectrum over [lo, hi] (trapezoids are exact here)."""
    inside = lam[(lam > lo) & (lam < hi)]
    x = np.concatenate([[lo], inside, [hi]])
    y = np.interp(x, lam, val, left=0.0, right=0.0)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def check_support(spectrum: Spectrum, lo: float = 380.0, hi: float = 780.0, where: str | None = None) -> None:
    """Raise :class:`SpectrumError` if ``spectrum`` has no energy inside ``[lo, hi]`` nm.

    Parameters
    ----------
    spectrum : Spectrum
        The spectrum to check.
    lo, hi : float
        The wavelength range a table will cover, nm.
    where : str, optional
        ``path:line`` to name in the message (defaults to ``spectrum.source``).
    """
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise SpectrumError(f"invalid wavelength range [{lo}, {hi}] nm")
    if not _energy_inside(spectrum.wavelengths, spectrum.values, lo, hi) > 0.0:
        raise SpectrumError(
            f"{where or spectrum.source}: spectrum '{spectrum.name}' has no energy inside "
            f"[{lo:g}, {hi:g}] nm (its samples span {spectrum.wavelengths[0]:g}-"
            f"{spectrum.wavelengths[-1]:g} nm and are zero in that range)"
        )


# --------------------------------------------------------------------------------------
# Built-in spectra (colour-science)
# --------------------------------------------------------------------------------------

def _lookup(table, name: str, kind: str, prefix: str):
    """Find ``name`` in a colour-science dataset, exactly or ignoring case."""
    keys = list(table.keys())
    key = name if name in keys else {k.lower(): k for k in keys}.get(name.lower())
    if key is None:
        known = ", ".join(sorted(table.keys(), key=str.lower))
        raise SpectrumError(f"{prefix}{name}: unknown {kind}; known names: {known}")
    return key, table[key]


def cie_illuminant(name: str) -> Spectrum:
    """A standard illuminant that colour-science ships (``colour.SDS_ILLUMINANTS``), by name."""
    from . import colour_data  # colour-science's data, without importing it each run

    key, (wl, val) = _lookup(colour_data.spectra("illuminants"), name, "CIE illuminant", "cie:")
    return make_spectrum(key, f"cie:{key}", wl, val)


def light_source(name: str) -> Spectrum:
    """A light source that colour-science ships (``colour.SDS_LIGHT_SOURCES``), by name."""
    from . import colour_data

    key, (wl, val) = _lookup(colour_data.spectra("light_sources"), name, "light source", "lamp:")
    return make_spectrum(key, f"lamp:{key}", wl, val)


# --------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------

def _read_text(path: Path) -> str:
    """The text of a spectrum file: a regular file of at most 64 MiB (design §3.3), so that a
    device or FIFO named as a spectrum fails at once instead of hanging or filling memory."""
    return read_input_text(path, "spectrum", SpectrumError, MAX_INPUT_BYTES)


def _number(token: str, where: str) -> float:
    try:
        return float(token)
    except ValueError:
        raise SpectrumError(f"{where}: cannot parse number {token!r}") from None


def read_spd(path: str | Path, lo: float | None = 380.0, hi: float | None = 780.0) -> Spectrum:
    """Read a pbrt ``.spd`` file: ``lambda value`` pairs (nm), whitespace separated.

    ``#`` starts a comment that runs to the end of the line. Pairs may span lines.
    The spectrum must have energy inside ``[lo, hi]`` nm (not checked if ``lo`` is None).
    """
    path = Path(path)
    text = _read_text(path)
    tokens: list[tuple[str, int]] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        for tok in line.split("#", 1)[0].split():
            tokens.append((tok, lineno))
    if not tokens:
        raise SpectrumError(f"{path}:1: no data (expected 'lambda value' pairs)")
    if len(tokens) % 2:
        tok, lineno = tokens[-1]
        raise SpectrumError(f"{path}:{lineno}: odd number of values ({len(tokens)}): "
                            f"wavelength {tok} has no value")
    nums = [_number(t, f"{path}:{n}") for t, n in tokens]
    lines = [n for _, n in tokens[0::2]]
    sp = make_spectrum(path.stem, str(path), nums[0::2], nums[1::2], where=str(path), lines=lines)
    if lo is not None and hi is not None:
        check_support(sp, lo, hi, where=f"{path}:{lines[0]}")
    return sp


def _lspdd_name(meta: dict[str, str], fallback: str) -> str:
    """The lamp's name from the LSPDD Brand / Model / Category lines ('null' is empty)."""
    def get(key: str) -> str:
        v = meta.get(key, "").strip()
        return "" if v.lower() in ("", "null", "none") else v

    category = get("category")
    parts: list[str] = []
    for v in (get("brand"), get("model")):
        if v and v.lower() not in [p.lower() for p in parts] + [category.lower()]:
            parts.append(v)
    if category and category.lower() not in (p.lower() for p in parts):
        parts.append(f"({category})" if parts else category)
    return " ".join(parts) or fallback


def _fill_gaps(lam: list[float], val: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Zero-filled spectrum of an LSPDD export, whose zero-intensity rows are left out.

    The base step is the most common spacing. Where two rows are further apart than that, the
    rows in between were zeros: a zero sample goes one base step after the earlier row and
    one before the later row, so the piecewise-linear spectrum is zero across the gap. The
    same is done one step before the first row and after the last, where zero rows may also
    have been dropped (outside them the spectrum is zero anyway).
    """
    x = np.asarray(lam, dtype=np.float64)
    y = np.asarray(val, dtype=np.float64)
    if x.size < 2:
        return x, y
    steps = np.diff(x)
    base = Counter(np.round(steps, 6).tolist()).most_common(1)[0][0]
    if not base > 0:
        return x, y
    tol = 1e-6 * base
    out_x: list[float] = [x[0] - base]
    out_y: list[float] = [0.0]
    for i in range(x.size):
        out_x.append(x[i])
        out_y.append(y[i])
        if i + 1 == x.size:
            break
        gap = x[i + 1] - x[i]
        if gap <= base + tol:
            continue
        a, b = x[i] + base, x[i + 1] - base
        if b - a > tol:
            out_x += [a, b]
            out_y += [0.0, 0.0]
        else:  # one missing row (or an irregular gap shorter than two steps): one zero
            out_x.append(0.5 * (a + b) if b < a else a)
            out_y.append(0.0)
    out_x.append(x[-1] + base)
    out_y.append(0.0)
    return np.array(out_x), np.array(out_y)


_HEADER = re.compile(r"^\s*wavelength\s*,\s*intensity\s*$", re.IGNORECASE)


def read_lspdd_csv(path: str | Path, lo: float | None = 380.0,
                   hi: float | None = 780.0) -> Spectrum:
    """Read an LSPDD CSV export.

    Format: ``# Key : Value`` lines (Category, Brand, Model, ... give the lamp's name), a
    ``wavelength, intensity`` header, then ``lambda,value`` rows, nm and arbitrary units,
    on an irregular grid. Rows with zero intensity are left out of these exports, so gaps
    are filled with zeros (see :func:`_fill_gaps`). The spectrum must have energy inside
    ``[lo, hi]`` nm (not checked if ``lo`` is None).
    """
    path = Path(path)
    text = _read_text(path)
    meta: dict[str, str] = {}
    lam: list[float] = []
    val: list[float] = []
    lines: list[int] = []
    seen_header = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            key, sep, value = line[1:].partition(":")
            if sep:
                meta.setdefault(key.strip().lower(), value.strip())
            continue
        if not seen_header and not lam and _HEADER.match(line):
            seen_header = True
            continue
        fields = [f.strip() for f in line.split(",")]
        if fields and fields[-1] == "":
            fields.pop()
        where = f"{path}:{lineno}"
        if len(fields) != 2:
            if not lam and not seen_header:
                raise SpectrumError(f"{where}: expected the header 'wavelength, intensity' "
                                    f"or a 'lambda,value' row, got {line[:60]!r}")
            raise SpectrumError(f"{where}: expected 2 comma-separated columns "
                                f"(wavelength, intensity), got {len(fields)}")
        lam.append(_number(fields[0], where))
        val.append(_number(fields[1], where))
        lines.append(lineno)
    if not lam:
        raise SpectrumError(f"{path}:{len(text.splitlines()) or 1}: no data rows "
                            f"(expected 'lambda,value' rows after the header)")
    name = _lspdd_name(meta, path.stem)
    # Validate the rows as given (so errors point at file lines), then fill the gaps.
    make_spectrum(name, str(path), lam, val, where=str(path), lines=lines)
    x, y = _fill_gaps(lam, val)
    sp = make_spectrum(name, str(path), x, y, where=str(path))
    if lo is not None and hi is not None:
        check_support(sp, lo, hi, where=f"{path}:{lines[0]}")
    return sp


# --------------------------------------------------------------------------------------
# Dispatch
# --------------------------------------------------------------------------------------

#: Spectrum readers by file suffix: a function ``(path, selector, lo, hi) -> [Spectrum]`` or
#: ``"module:function"``, imported on first use (the scene reader builds on this module, so
#: naming it keeps the imports one-way). ``register_reader`` adds one.
READERS: dict[str, Any] = {
    ".csv": lambda path, sel, lo, hi: [read_lspdd_csv(path, lo, hi)],
    ".spd": lambda path, sel, lo, hi: [read_spd(path, lo, hi)],
    ".pbrt": "wavelength_pdf.scene_spectra:read_scene",
}


def register_reader(suffix: str, reader: Callable[..., list] | str) -> None:
    """Read files ending in ``suffix`` with ``reader(path, selector, lo, hi)``."""
    READERS[suffix.lower()] = reader


def _reader(suffix: str) -> Callable[..., list]:
    reader = READERS[suffix]
    if isinstance(reader, str):
        import importlib

        module, _, name = reader.partition(":")
        reader = READERS[suffix] = getattr(importlib.import_module(module), name)
    return reader


def _split_selector(spec: str) -> tuple[str, str | None]:
    """``scene.pbrt#1`` -> (``scene.pbrt``, ``1``); other specs are returned unchanged."""
    if "#" in spec:
        base, sel = spec.rsplit("#", 1)
        if base.lower().endswith(".pbrt"):
            return base, sel
    return spec, None


def load_spectra(spec: str, lo: float = 380.0, hi: float = 780.0) -> list[Spectrum]:
    """All spectra named by ``spec`` (one, except for a scene with several emitters).

    Parameters
    ----------
    spec : str
        ``cie:NAME``, ``lamp:NAME``, or a path to a ``.pbrt`` scene (optionally ``#N`` or
        ``#NAME`` to pick one emitter), a ``.spd`` file or an LSPDD ``.csv`` export.
    lo, hi : float
        The wavelength range the table will cover, nm: every spectrum must have energy in it.

    Raises
    ------
    SpectrumError
        Unknown name, unreadable or malformed file, or no energy inside ``[lo, hi]``.
    """
    spec = str(spec)
    low = spec.lower()
    if low.startswith("cie:"):
        sps = [cie_illuminant(spec[4:])]
    elif low.startswith("lamp:"):
        sps = [light_source(spec[5:])]
    else:
        base, sel = _split_selector(spec)
        suffix = Path(base).suffix.lower()
        if suffix not in READERS:
            if not Path(base).exists():
                raise SpectrumError(f"{base}: no such file (and not cie:NAME or lamp:NAME)")
            raise SpectrumError(f"{base}: unknown spectrum format '{suffix or '(none)'}' "
                                f"(expected {', '.join(READERS)}, cie:NAME or lamp:NAME)")
        return _reader(suffix)(base, sel, lo, hi)
    for sp in sps:
        check_support(sp, lo, hi)
    return sps


def load_spectrum(spec: str, lo: float = 380.0, hi: float = 780.0) -> Spectrum:
    """Exactly one spectrum named by ``spec`` (see :func:`load_spectra`).

    A scene with several distinct emitters is an error that lists them, unless one is
    picked with ``scene.pbrt#N`` (index from 0) or ``scene.pbrt#NAME``.
    """
    sps = load_spectra(spec, lo, hi)
    if len(sps) != 1:
        listing = "; ".join(f"#{i}: {s.name} ({s.source})" for i, s in enumerate(sps))
        raise SpectrumError(
            f"{spec}: the scene has {len(sps)} distinct emitter spectra; pick one with "
            f"'{spec}#N': {listing}"
        )
    return sps[0]
