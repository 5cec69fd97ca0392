"""Stratified tables of a spectrum: four equal-mass bands, no optimizer (design §1.7).

The simple samplers every optimized table is measured against (docs/benchmark.md), written as
ordinary tables (design §1, §2) so that one code path samples them all:

- ``spd``, ``luminance``, ``xyz``: stratified sampling of a lamp's own spectrum I (Evans and
  McCool 1999), of I times the luminance curve ybar, or of I times xbar + ybar + zbar (the
  weight of the optimizer's starting point, :mod:`wavelength_pdf.init`), cut into four bands of
  equal mass, density k carrying band k;
- ``uniform``: the same construction for a constant over the table's range (stratified uniform
  sampling as a table);
- ``visible``: pbrt-v4's visible density, sech^2(0.0072 (lambda - 538 nm)) on 360-830 nm, as a
  table. pbrt-v4 draws its four wavelengths from that one density at u + j/4; the table draws
  them from four bands of equal mass at (u + k)/4: the same four quantiles, since
  {(u + j/4) mod 1} = {(v + k)/4} with v = 4u mod 1, and the same balance-heuristic weight
  (the mixture of the four bands is the density itself). Only the map from u to the
  quadruple differs.

The construction (:func:`equal_mass_table`) is the rule of design §1.7, which the C++ header
(``wavelength_table::EqualMassTable``) follows too; both are pinned by the cross-language test
vectors of ``scripts/make_test_vectors.py``. Written here because no library builds
equal-mass piecewise-linear partitions on a shared grid.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from wavelength_pdf.model import N_DENSITIES, RANGE, trapezoid
from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.table import Table

__all__ = ["WEIGHTS", "METHODS", "CUT_WIDTH_NM", "equal_mass_table", "weighted_spectrum",
           "stratified_table", "uniform_table", "visible_table", "VISIBLE_RANGE_PBRT",
           "visible_density"]

#: The weights of the stratified constructions: q = I * w.
WEIGHTS = ("spd", "luminance", "xyz")
#: Every simple sampler this module writes as a table.
METHODS = ("uniform", "visible", *WEIGHTS)
#: Width of the step in which a density hands over to the next at a cut (design §1.7).
CUT_WIDTH_NM = 0.01
#: pbrt-v4's visible-sampling range, nm.
VISIBLE_RANGE_PBRT = (360.0, 830.0)
#: Node spacing at which the visible density is tabulated (its linear interpolant is then
#: within 2e-5 of it, relatively).
VISIBLE_STEP_NM = 0.5


class StratifiedError(ValueError):
    """Input the construction cannot use (no mass, bad nodes); the message says why."""


def _step(x: np.ndarray, a: float) -> float:
    """The hand-over step at a cut a: CUT_WIDTH_NM, or half the gap to the next node."""
    j = int(np.searchsorted(x, a, side="right"))
    return min(CUT_WIDTH_NM, 0.5 * (x[j] - a)) if j < x.size else 0.0


def _cuts(x: np.ndarray, q: np.ndarray, mass: np.ndarray) -> list[float]:
    """The cuts a_1 <= a_2 <= a_3 at which the four bands, each with its hand-over steps,
    carry equal mass: g(a_k) = k M / 4 with g(a) = Q(a) + q(a) d(a) / 2 (design §1.7).

    g is the mass of q up to a plus the part of the step [a, a + d] that stays with the band
    before the cut; it is continuous and increasing inside a segment and jumps up at a node,
    so the segment is found among the nodes and the cut by bisection in it (a target inside
    a jump: the node)."""
    total = mass[-1]
    h = np.diff(x)
    g_right = mass[:-1] + q[:-1] * np.minimum(CUT_WIDTH_NM, 0.5 * h) / 2.0  # g at x_i from the right
    cuts: list[float] = []
    for k in range(1, N_DENSITIES):
        t = total * k / N_DENSITIES
        # Segment i: g(x_i+) <= t < g(x_{i+1}-) = Q_{i+1}; a target in the jump at x_i is x_i.
        i = int(np.clip(np.searchsorted(mass, t, side="right") - 1, 0, x.size - 2))
        if t <= g_right[i]:
            cuts.append(float(x[i]))
            continue
        lo, hi = 0.0, float(h[i])
        q0, slope = float(q[i]), float((q[i + 1] - q[i]) / h[i])
        while True:
            s = 0.5 * (lo + hi)
            if s <= lo or s >= hi:
                break
            g = mass[i] + (q0 + 0.5 * slope * s) * s + (q0 + slope * s) * min(CUT_WIDTH_NM, 0.5 * (h[i] - s)) / 2.0
            if g < t:
                lo = s
            else:
                hi = s
        cuts.append(float(x[i] + hi))
    return cuts


def equal_mass_table(x, q, *, name: str = "") -> Table:
    """Four densities that cut ``q`` into bands of equal mass (design §1.7).

    Parameters
    ----------
    x : (n,) array
        Nodes, nm, strictly increasing, n >= 2; the table covers [x[0], x[-1]].
    q : (n,) array
        The weight to stratify, finite and >= 0 at the nodes, linear between them, with a
        positive integral. Only its shape matters: it is scaled to a peak of 1, and values
        below 1e-300 of the peak count as 0 (design §3.3).

    Returns
    -------
    Table
        On the nodes x plus, at each cut a_k (k = 1..3), the nodes a_k and a_k + d_k, where
        d_k = min(0.01 nm, half the gap to the next node): density k - 1 equals q on its
        band up to a_k and falls linearly to 0 at a_k + d_k, where density k rises from 0 to
        q; each density is 0 at every other node and is normalized by the trapezoid rule.
        The cuts give every density the same mass M / 4 before normalizing (M the mass of
        q), so the mixture (1/4) sum_k p_k equals q / M wherever q is linear between the
        nodes: the table importance-samples q exactly and stratifies it in four bands. Only
        where two cuts fall within two steps of each other (a line narrower than 0.02 nm
        holding more than a quarter of the mass) is the step shortened to fit, and the
        masses then differ slightly. A band without mass becomes q itself.

    Raises
    ------
    StratifiedError
        Fewer than 2 nodes, nodes not strictly increasing or not finite, a negative or
        non-finite q, or q without mass.
    """
    x = np.asarray(x, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    what = f"{name}: " if name else ""
    if x.ndim != 1 or q.shape != x.shape or x.size < 2:
        raise StratifiedError(f"{what}need at least 2 nodes and one weight per node")
    if not (np.all(np.isfinite(x)) and np.all(np.diff(x) > 0)):
        raise StratifiedError(f"{what}nodes must be finite and strictly increasing")
    if not np.all(np.isfinite(q)) or np.any(q < 0):
        raise StratifiedError(f"{what}the weight must be finite and non-negative")
    # Scaled to a peak of 1, values below 1e-300 of it read as 0 (design §3.3): a density
    # normalized from them would underflow to 0 where q is not 0.
    peak = q.max()
    if peak > 0:
        q = q / peak
        q[q < 1e-300] = 0.0
    seg = 0.5 * (q[1:] + q[:-1]) * np.diff(x)
    mass = np.concatenate([[0.0], np.cumsum(seg)])
    if not mass[-1] > 0 or not math.isfinite(mass[-1]):
        raise StratifiedError(f"{what}the weight has no mass over {x[0]:g}-{x[-1]:g} nm")
    lo, hi = float(x[0]), float(x[-1])
    cuts = _cuts(x, q, mass)
    starts = [lo]
    for k, a in enumerate(cuts):
        d = _step(x, a)
        if k + 1 < len(cuts) and cuts[k + 1] > a:
            d = min(d, 0.5 * (cuts[k + 1] - a))
        starts.append(a + d if a + d > a else a)
    grid = np.unique(np.concatenate([x, cuts, starts]))
    qg = np.interp(grid, x, q)
    ends = [*cuts, hi]
    pdfs = np.zeros((N_DENSITIES, grid.size))
    whole = qg / trapezoid(grid, qg)
    for k in range(N_DENSITIES):
        band = (grid >= starts[k]) & (grid <= ends[k])
        p = np.where(band, qg, 0.0)
        m = trapezoid(grid, p)
        pdfs[k] = p / m if m > 0 else whole
    return Table(grid=grid, pdfs=pdfs)


def _weight(weight: str) -> Callable[[np.ndarray], np.ndarray] | None:
    """The weight function w(lambda) of a stratified method (None: w = 1) and its nodes."""
    if weight == "spd":
        return None
    from wavelength_pdf.colorimetry import cmfs

    wl, cmf = cmfs()
    if weight == "luminance":
        col = cmf[:, 1]
    elif weight == "xyz":
        col = cmf.sum(axis=1)
    else:
        raise StratifiedError(f"unknown weight {weight!r}; choose from {', '.join(WEIGHTS)}")
    return lambda lam: np.interp(lam, wl, col, left=0.0, right=0.0)


def weighted_spectrum(spectrum: Spectrum, weight: str, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and values of q = I * w on [lo, hi]: the union of the spectrum's nodes, the
    weight's (the CMFs' 1 nm grid) and the ends, q taken linear between them (exact for the
    spectrum alone, ``weight="spd"``)."""
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise StratifiedError(f"the range must be finite with lo < hi, got {lo:g}-{hi:g}")
    w = _weight(weight)
    parts = [np.array([lo, hi]), spectrum.wavelengths]
    if w is not None:
        from wavelength_pdf.colorimetry import cmfs

        parts.append(cmfs()[0])
    x = np.unique(np.concatenate(parts))
    x = x[(x >= lo) & (x <= hi)]
    q = spectrum(x)
    if w is not None:
        q = q * w(x)
    return x, q


def stratified_table(spectrum: Spectrum, weight: str = "spd", lo: float = RANGE[0],
                     hi: float = RANGE[1]) -> Table:
    """Stratified sampling of ``spectrum`` times ``weight`` (one of :data:`WEIGHTS`) on
    [lo, hi] as a table (design §1.7); its comments say how it was made."""
    x, q = weighted_spectrum(spectrum, weight, lo, hi)
    table = equal_mass_table(x, q, name=spectrum.source)
    table.comments = [f"method: {weight}", f"name: {spectrum.name}", f"source: {spectrum.source}",
                      f"stratified sampling of {_DESCRIBE[weight]} (four equal-mass bands, design §1.7)"]
    return table


_DESCRIBE = {"spd": "the spectrum", "luminance": "the spectrum times ybar",
             "xyz": "the spectrum times xbar + ybar + zbar"}


def uniform_table(lo: float = RANGE[0], hi: float = RANGE[1]) -> Table:
    """Stratified uniform sampling of [lo, hi] as a table: four bands of equal width."""
    table = equal_mass_table(np.array([lo, hi]), np.ones(2))
    table.comments = ["method: uniform", f"stratified uniform sampling of {lo:g}-{hi:g} nm as a table "
                      "(four equal bands, design §1.7)"]
    return table


def visible_density(lam) -> np.ndarray:
    """pbrt-v4's visible-sampling density shape, sech^2(0.0072 (lambda - 538)) (unnormalized)."""
    return 1.0 / np.cosh(0.0072 * (np.asarray(lam, dtype=np.float64) - 538.0)) ** 2


def visible_table(lo: float = VISIBLE_RANGE_PBRT[0], hi: float = VISIBLE_RANGE_PBRT[1]) -> Table:
    """pbrt-v4's visible sampling as a table: its density on [lo, hi] (default pbrt-v4's
    360-830 nm) tabulated every 0.5 nm and cut into four equal-mass bands."""
    n = int(round((hi - lo) / VISIBLE_STEP_NM))
    x = np.linspace(lo, hi, max(n, 1) + 1)
    table = equal_mass_table(x, visible_density(x))
    table.comments = ["method: visible", "pbrt-v4's visible density sech^2(0.0072 (lambda - 538)) "
                      f"on {lo:g}-{hi:g} nm as a table (four equal-mass bands, design §1.7)"]
    return table
