"""Where a table cannot sample a spectrum's light (design §1.5).

A path only carries wavelengths where the table's mixture density sum_k p_k is positive.
Where the lamp emits but the mixture is zero, its light is missing from every render made
with the table, however many samples it takes. Two places can hide such emission:

- a *gap* inside the table's range, an interval where all four densities vanish together
  (densities are linear between nodes, so a gap is a run of segments whose end nodes are all
  zero); the defensive mixture (renderer option ``--wavelength-pdf-defensive S``) removes it;
- the stretches *outside* the table's range [lambda_0, lambda_M] inside 360..830 nm, where
  the colour matching functions are defined; the defensive mixture is uniform over the
  table's own range and cannot help there, only a table over a wider range can.

The rule is the renderer's (``renderer/src/pbrt/wavelength_coverage.h``): every gap where the
lamp emits is reported; emission outside the range only when it carries more than
``OUTSIDE_LUMINANCE_FRACTION`` of the lamp's luminance or ``OUTSIDE_TRISTIMULUS_FRACTION``
of any of X, Y, Z (a table on 380..780 nm misses ~1e-5 of the luminance of a lamp with a
flat floor over 360..830 nm; 1e-3 of a tristimulus value is ~0.1 CIEDE2000). One difference:
this package reads a spectrum as zero outside its samples (design §3), where pbrt-v4
extends a sampled spectrum with its end values, so for a spectrum that stops at a non-zero
value the renderer can find emission outside the range that this module does not.

The fractions are exact integrals of piecewise-linear products (spectrum times CMF on the
union of their nodes and the table's), not a sampled sum.
"""
from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np

from .colorimetry import cmfs
from .model import product_integrals

#: Emission outside the table's range above this fraction of the luminance is reported.
OUTSIDE_LUMINANCE_FRACTION = 1e-4
#: ... or above this fraction of any tristimulus value (X, Y or Z).
OUTSIDE_TRISTIMULUS_FRACTION = 1e-3
#: The defensive share the warnings suggest (design §1.5).
SUGGESTED_DEFENSIVE_SHARE = 0.01
#: Emission outside the table's range above this fraction of the luminance or of any of
#: X, Y, Z: ``optimize`` and ``batch`` refuse the spectrum before any work (design §3.3).
REFUSE_OUTSIDE_FRACTION = 1e-2
#: The range a refusal suggests stays inside the renderer's (and the CMFs') 360..830 nm, on
#: whole multiples of this step (nm), so that ``--grid-step`` 5 divides it.
SUGGESTED_RANGE_STEP = 5.0

Interval = tuple[float, float]


@dataclass(frozen=True)
class Coverage:
    """How much of one spectrum's light a table never samples.

    Attributes
    ----------
    gaps : list of (float, float)
        Zero-mixture intervals inside the table's range (nm) where the spectrum emits.
    gap_luminance_fraction : float
        Share of the spectrum's luminance (Y over 360..830 nm) inside those gaps.
    outside : list of (float, float)
        Stretches outside the table's range but inside 360..830 nm where it emits (nm).
    outside_luminance_fraction : float
        Share of its luminance there.
    outside_tristimulus_fraction : float
        The largest share of X, Y or Z there.
    table_range : (float, float)
        The table's range, nm.
    """

    gaps: list[Interval]
    gap_luminance_fraction: float
    outside: list[Interval]
    outside_luminance_fraction: float
    outside_tristimulus_fraction: float
    table_range: Interval

    @property
    def outside_matters(self) -> bool:
        """True when the emission outside the range is above the reporting thresholds."""
        return bool(self.outside) and (
            self.outside_luminance_fraction > OUTSIDE_LUMINANCE_FRACTION
            or self.outside_tristimulus_fraction > OUTSIDE_TRISTIMULUS_FRACTION)

    def warnings(self, who: str = "the spectrum") -> list[str]:
        """The warning texts (empty when the table covers the spectrum)."""
        lo, hi = self.table_range
        out = []
        if self.gaps:
            out.append(
                f"{who}: the table's mixture density is zero on {_intervals(self.gaps)}, where "
                f"the spectrum emits ({_percent(self.gap_luminance_fraction)} of its "
                "luminance): renders never sample those wavelengths and are biased; render with "
                f"--wavelength-pdf-defensive {SUGGESTED_DEFENSIVE_SHARE:g} (a uniform share over "
                "the table's range, design §1.5)")
        if self.outside_matters:
            out.append(
                f"{who}: the spectrum emits on {_intervals(self.outside)}, outside the table's "
                f"range [{lo:g}, {hi:g}] nm: renders with the table miss "
                f"{_percent(self.outside_luminance_fraction)} of its luminance (up to "
                f"{_percent(self.outside_tristimulus_fraction)} of X, Y or Z); "
                "--wavelength-pdf-defensive only covers the table's range: optimize a table over "
                "a wider range (optimize --range LO HI --grid-step NM)")
        return out


def _percent(f: float) -> str:
    return f"{100.0 * f:.3g}%"


def _intervals(v: list[Interval]) -> str:
    parts = [f"[{a:g}, {b:g}]" for a, b in v]
    text = parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]
    return text + " nm"


def zero_mixture_intervals(grid: np.ndarray, pdfs: np.ndarray) -> list[Interval]:
    """Maximal intervals of ``grid`` on which all densities are zero (as the renderer's
    ``ZeroMixtureIntervals``): runs of segments whose two end nodes are zero in every row."""
    grid = np.asarray(grid, dtype=np.float64)
    zero = np.all(np.asarray(pdfs) <= 0, axis=0)
    out: list[Interval] = []
    for i in np.flatnonzero(zero[:-1] & zero[1:]):
        a, b = float(grid[i]), float(grid[i + 1])
        if out and out[-1][1] == a:
            out[-1] = (out[-1][0], b)
        else:
            out.append((a, b))
    return out


def coverage(grid: np.ndarray, pdfs: np.ndarray, spectrum) -> Coverage:
    """Where the table (``grid``, ``pdfs`` (4, M+1)) misses the light of ``spectrum``.

    ``spectrum`` is any object with ``wavelengths`` and ``values`` (linear between them,
    zero outside; :class:`wavelength_pdf.spectra.Spectrum`). Luminance and tristimulus
    shares are of its integrals over the CMFs' range (360..830 nm).
    """
    grid = np.asarray(grid, dtype=np.float64)
    lo, hi = float(grid[0]), float(grid[-1])
    cwl, cval = cmfs()
    a, b = float(cwl[0]), float(cwl[-1])
    wl = np.asarray(spectrum.wavelengths, dtype=np.float64)
    val = np.asarray(spectrum.values, dtype=np.float64)
    # Scale to a peak of 1 first (fractions do not depend on it; products cannot overflow).
    peak = float(np.max(val)) if val.size else 0.0
    val = val / peak if peak > 0 else val
    gaps = zero_mixture_intervals(grid, pdfs)
    cuts = [lo, hi] + [e for g in gaps for e in g]
    x = np.unique(np.concatenate([wl, cwl, grid, cuts]))
    x = x[(x >= a) & (x <= b)]
    s = np.interp(x, wl, val, left=0.0, right=0.0)
    inside = (x[:-1] >= wl[0]) & (x[1:] <= wl[-1])  # wl[0] and wl[-1] are nodes of x
    s0, s1 = np.where(inside, s[:-1], 0.0), np.where(inside, s[1:], 0.0)
    c = np.stack([np.interp(x, cwl, cval[:, i], left=0.0, right=0.0) for i in range(3)], axis=1)
    # Emission itself (a CMF of 1) as a fourth column: a gap "emits" where the spectrum does,
    # even where the CMFs are tiny.
    seg = product_integrals(x, s0, s1, np.column_stack([c, np.ones(x.size)]))
    mid = 0.5 * (x[1:] + x[:-1])
    total = seg[:, :3].sum(axis=0)

    found_gaps = []
    in_gaps = np.zeros(4)
    for g0, g1 in gaps:
        part = seg[(mid > g0) & (mid < g1)].sum(axis=0)
        if part[3] > 0:
            found_gaps.append((g0, g1))
            in_gaps += part
    below, above = mid < lo, mid > hi
    outside_parts = seg[below | above].sum(axis=0)
    outside: list[Interval] = []
    emits = seg[:, 3] > 0
    if np.any(below & emits):  # from where the emission starts up to the table's range
        outside.append((float(x[:-1][below & emits].min()), lo))
    if np.any(above & emits):
        outside.append((hi, float(x[1:][above & emits].max())))

    def share(part: np.ndarray, k: int) -> float:
        return float(part[k] / total[k]) if total[k] > 0 else 0.0

    return Coverage(
        gaps=found_gaps, gap_luminance_fraction=share(in_gaps, 1), outside=outside,
        outside_luminance_fraction=share(outside_parts, 1),
        outside_tristimulus_fraction=max(share(outside_parts, k) for k in range(3)),
        table_range=(lo, hi))


def check_range(spectrum, lo: float, hi: float) -> list[str]:
    """The rule for emission at or beyond a table's ends (design §3.3), for ``optimize`` and
    ``batch`` before any work: renders with a table over [lo, hi] never sample the light the
    spectrum emits outside it, and the optimizer does not see it either (its J and bias are
    over the table's range).

    Returns the warnings of :meth:`Coverage.warnings` when that light is above the reporting
    thresholds of design §1.5 (what ``show --spectrum`` and pbrt warn about).

    Raises
    ------
    wavelength_pdf.spectra.SpectrumError
        When it carries more than ``REFUSE_OUTSIDE_FRACTION`` of the luminance or of any of
        X, Y, Z: the message names the share, where the light is and a range that covers it.
    """
    from .spectra import SpectrumError

    cov = coverage(np.array([lo, hi], dtype=np.float64), np.ones((4, 2)), spectrum)
    if not cov.outside:
        return []
    if max(cov.outside_luminance_fraction, cov.outside_tristimulus_fraction) > REFUSE_OUTSIDE_FRACTION:
        step = SUGGESTED_RANGE_STEP
        a = min(x for x, _ in cov.outside)
        b = max(y for _, y in cov.outside)
        wide_lo = min(lo, max(360.0, step * math.floor(a / step)))
        wide_hi = max(hi, min(830.0, step * math.ceil(b / step)))
        raise SpectrumError(
            f"{spectrum.source}: spectrum '{spectrum.name}' emits "
            f"{_percent(cov.outside_luminance_fraction)} of its luminance (up to "
            f"{_percent(cov.outside_tristimulus_fraction)} of X, Y or Z) on "
            f"{_intervals(cov.outside)}, outside the table's range [{lo:g}, {hi:g}] nm: renders "
            "with such a table never sample that light; optimize over a range that covers it, "
            f"e.g. --range {wide_lo:g} {wide_hi:g} --grid-step {step:g} (design §3.3)")
    return cov.warnings(spectrum.name) if cov.outside_matters else []
