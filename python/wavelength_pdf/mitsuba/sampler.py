"""The table's wavelength sampler (design §1) written for one Mitsuba 3 variant.

The same model as ``wavelength_pdf.sampling`` (the reference) and the header's
``SampleFour``: one u per path, lambda_k = F_k^-1(u) for the four densities, each inverse the
exact root of the segment's quadratic in the cancellation-free form 2 r / (a + sqrt(a^2 + 2 s r)),
solved from the end of the segment where the density is smaller; the estimator divides each
lane by the mixture density (1/4) sum_k p_k(lambda_j), the balance heuristic.

In the llvm and cuda variants every operation is a Dr.Jit array operation on the variant's
``Float64``, so Python runs once while a kernel is traced and never per path. In the scalar
variants the same formulas run on Python floats, per call.

The four densities share one u, so one search finds all four segments: the union of the four
CDFs' node values, sorted, cuts [0, 1] into intervals in each of which every density's segment
is fixed, and a table holds those four segments per interval; the segments are exactly the
per-density searches' (largest i with F_k[i] <= u, then the last segment with mass), because
a node value <= u is a member of the union <= u. The search itself starts from a guide table
over u (K equal bins, K = 2^16 by default: the first and last interval of each bin), so that
most lanes are done after two gathers, and finishes with a binary search between those two
in a Dr.Jit loop, which runs only as long as the packet's widest bin needs (log2 of its
interval count; the lines of a spiky lamp put a few hundred tiny-mass intervals into one
bin). Each density's segment then comes as one 8-value record (one packet gather) holding
what the inversion needs, with the slope precomputed: one division and one square root per
lane. With a 321-node table the sampler went from 52 ns per path (four searches) to 34 ns
(one merged binary search) to about 20 ns (guide table and records; wavelength_table/README.md).
Mitsuba's own
``IrregularContinuousDistribution`` would do the search too, but its float32 inversion
subtracts nearly equal numbers on steep segments and cannot reproduce the reference on a
0.05 nm spike to 1e-5, so the inversion is written here (in double precision, as the header
keeps the table).
"""
from __future__ import annotations

import bisect
import math

import drjit as dr
import numpy as np

from wavelength_pdf.model import normalized_with_cdf
from wavelength_pdf.table import N_DENSITIES, Table, TableError, normalize


def defensive_mixture(table: Table, share: float) -> Table:
    """(1 - share) p_k + share / (lambda_M - lambda_0) for every k (design §1), renormalized."""
    share = float(share)
    if not (0.0 <= share <= 1.0):
        raise TableError(f"defensive share must be in [0, 1], got {share!r}")
    grid = np.asarray(table.grid, dtype=np.float64)
    pdfs = (1.0 - share) * np.asarray(table.pdfs, dtype=np.float64) + share / (grid[-1] - grid[0])
    return Table(grid=grid.copy(), pdfs=normalize(grid, pdfs), comments=list(table.comments))


def _normalized_with_cdf(grid: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Node values, CDF at the nodes (F[0] = 0, F[M] = 1) and the last segment with mass:
    ``model.normalized_with_cdf`` in numpy, the formulas of ``wavelength_pdf.sampling``. (The
    table is prepared here, outside Dr.Jit; only the sampling runs in Dr.Jit types.)"""
    pn, cdf = normalized_with_cdf(grid, p)
    has_mass = (p[1:] + p[:-1]) > 0
    last = int(len(has_mass) - 1 - np.argmax(has_mass[::-1]))
    return pn, cdf, last


class TableSampler:
    """Four piecewise-linear densities on one grid, sampled with one u per path.

    Parameters
    ----------
    table : Table
        As read by ``wavelength_pdf.table.read_table`` (validated, normalized).
    module : module
        A Mitsuba variant module, e.g. ``mitsuba.llvm_ad_spectral``; its ``Float64`` and
        ``UInt32`` are the array types of the computation.
    defensive : float
        Share S of the uniform density mixed into every p_k (design §1); 0 keeps the table.
    guide_bins : int
        K, the guide table's bins over u (module docstring): a power of two, so that u K and
        b / K are exact; any such K gives the same segments, a larger K fewer search steps.
    """

    def __init__(self, table: Table, module, defensive: float = 0.0, guide_bins: int = 1 << 16):
        if defensive:
            table = defensive_mixture(table, defensive)
        if not (isinstance(guide_bins, int) and 1 <= guide_bins <= 1 << 24 and guide_bins & (guide_bins - 1) == 0):
            raise ValueError(f"guide_bins must be a power of two in [1, 2^24], got {guide_bins!r}")
        self.table = table
        self.m = module
        self.jit = dr.is_jit_v(module.Float)
        grid = np.asarray(table.grid, dtype=np.float64)
        self.n = int(grid.size)
        self.lo, self.hi = float(grid[0]), float(grid[-1])
        parts = [_normalized_with_cdf(grid, np.asarray(p, dtype=np.float64)) for p in table.pdfs]
        self.last = [last for _, _, last in parts]
        # The mixture at the nodes: linear interpolation commutes with the mean, so the mixture
        # inside a segment is one interpolation (2 gathers a lane instead of 8).
        mix = np.mean([pn for pn, _, _ in parts], axis=0)
        h = np.diff(grid)
        # The merged search (module docstring): sorted distinct node values of the four CDFs
        # (the last node, F = 1, starts no segment) and each interval's four segments.
        keys = [F[:-1] for _, F, _ in parts]
        merged = np.unique(np.concatenate(keys))
        segs = np.stack([np.searchsorted(K, merged, side="right") - 1 for K in keys], axis=1)
        segs = np.minimum(segs, np.asarray(self.last)[None, :]).astype(np.uint32)
        self.n_merged = int(merged.size)
        # Guide: the interval holding u = b / K for b = 0..K (0 when u is below every key). An
        # interval index of u in [b/K, (b+1)/K) lies between guide[b] and guide[b+1].
        self.guide_bins = guide_bins
        guide = np.maximum(np.searchsorted(merged, np.arange(guide_bins + 1) / guide_bins, side="right") - 1, 0)
        # Each density's segment record: left node x0, width h, the density A at the end the
        # root is taken from (the smaller one), 2 x the slope seen from that end, the CDF Fb
        # there, the direction sigma (+1 from the left, -1 from the right), the mixture at the
        # left node and its slope. The root t' >= 0 of (SG2 / 4) t'^2 + A t' = sigma (u - Fb)
        # is then one division and one square root, and t = t' (left) or h - t' (right).
        records = []
        for pn, F, _ in parts:
            p0, p1 = pn[:-1], pn[1:]
            slope = (p1 - p0) / h
            right = p1 < p0
            records.append(np.stack([grid[:-1], h, np.where(right, p1, p0), 2.0 * np.where(right, -slope, slope),
                                     np.where(right, F[1:], F[:-1]), np.where(right, -1.0, 1.0),
                                     mix[:-1], (mix[1:] - mix[:-1]) / h], axis=1))
        if self.jit:
            F64 = module.Float64
            self._grid = F64(grid)
            self._pn = [F64(pn) for pn, _, _ in parts]
            self._F = [F64(F) for _, F, _ in parts]
            self._mix = F64(mix)
            # +inf closes the last interval.
            self._merged = F64(np.append(merged, np.inf))
            self._segs = module.UInt32(segs.ravel())
            self._guide = module.UInt32(guide.astype(np.uint32))
            self._records = [F64(r.ravel()) for r in records]
            dr.eval(self._grid, self._pn, self._F, self._mix, self._merged, self._segs, self._guide, self._records)
        else:
            self._grid = [float(v) for v in grid]
            self._pn = [[float(v) for v in pn] for pn, _, _ in parts]
            self._F = [[float(v) for v in F] for _, F, _ in parts]
            self._mix = [float(v) for v in mix]
            self._merged = [float(v) for v in merged]
            self._segs = [[int(v) for v in row] for row in segs]
            self._records = [[tuple(float(v) for v in row) for row in r] for r in records]

    # --- elementary operations: Dr.Jit arrays (jit) or Python floats (scalar) ------------

    def _at(self, values, i):
        return dr.gather(self.m.Float64, values, i) if self.jit else values[i]

    def _interval(self, values, x):
        """Largest i in [0, n-2] with values[i] <= x (0 when none is)."""
        if self.jit:
            return self.m.math.find_interval(self.n, lambda idx: dr.gather(self.m.Float64, values, idx) <= x)
        return min(max(bisect.bisect_right(values, x) - 1, 0), self.n - 2)

    def _select(self, cond, a, b):
        return dr.select(cond, a, b) if self.jit else (a if cond else b)

    def _clip(self, x, lo, hi):
        return dr.clip(x, lo, hi) if self.jit else min(max(x, lo), hi)

    # --- sample / pdf / invert ----------------------------------------------------------

    def sample_segment(self, k: int, u):
        """Segment i and offset t [nm] of lambda = F_k^-1(u); u in [0, 1] (Float64)."""
        u = self._clip(u, 0.0, 1.0)
        i = self._four_segments(u)[k]
        return i, self._solve(k, i, u)[0]

    def _four_segments(self, u):
        """The segments of F_k^-1(u) for k = 0..3 from one merged search; u in [0, 1]."""
        if not self.jit:
            return self._segs[max(bisect.bisect_right(self._merged, u) - 1, 0)]
        m = self.m
        b = dr.minimum(m.UInt32(u * self.guide_bins), self.guide_bins - 1)  # exact: K is a power of two
        lo, hi = dr.gather(m.UInt32, self._guide, b), dr.gather(m.UInt32, self._guide, b + 1)

        def halve(lo, hi):  # keeps merged[lo] <= u (or lo = 0) and the answer in [lo, hi]
            mid = (lo + hi + 1) >> 1
            below = dr.gather(m.Float64, self._merged, mid) <= u
            return dr.select(below, mid, lo), dr.select(below, hi, mid - 1)

        q, _ = dr.while_loop(state=(lo, hi), cond=lambda lo, hi: lo < hi, body=halve)
        segs = dr.gather(m.ArrayXu, self._segs, q, shape=(N_DENSITIES, dr.width(q)))
        return [segs[k] for k in range(N_DENSITIES)]

    def _solve(self, k: int, i, u):
        """Offset t in segment i of density k where F_k = u, and the mixture density there;
        also the segment's left node. The root of the segment's quadratic in the
        cancellation-free form 2 r / (A + sqrt(A^2 + SG2 r)), r = sigma (u - Fb) >= 0."""
        if self.jit:
            rec = dr.gather(self.m.ArrayXf64, self._records[k], i, shape=(8, dr.width(u)))
            x0, h, A, SG2, Fb, sigma, mix0, mix_slope = (rec[j] for j in range(8))
            r = dr.maximum(sigma * (u - Fb), 0.0)
            den = A + dr.sqrt(dr.maximum(A * A + SG2 * r, 0.0))
            root = dr.select(den > 0, 2.0 * r / dr.select(den > 0, den, 1.0), 0.0)
            t = dr.clip(dr.select(sigma < 0, h - root, root), 0.0, h)
        else:
            x0, h, A, SG2, Fb, sigma, mix0, mix_slope = self._records[k][i]
            r = max(sigma * (u - Fb), 0.0)
            den = A + math.sqrt(max(A * A + SG2 * r, 0.0))
            root = 2.0 * r / den if den > 0 else 0.0
            t = min(max(h - root if sigma < 0 else root, 0.0), h)
        return t, mix0 + mix_slope * t, x0

    def sample(self, k: int, u):
        """lambda = F_k^-1(u) [nm]."""
        i, t = self.sample_segment(k, u)
        return self._at(self._grid, i) + t

    def pdf(self, lam):
        """Mixture density (1/4) sum_k p_k(lam) [1/nm]; 0 outside the grid."""
        inside = (lam >= self.lo) & (lam <= self.hi) if self.jit else self.lo <= lam <= self.hi
        lam_c = self._clip(lam, self.lo, self.hi)
        i = self._interval(self._grid, lam_c)
        x0, a = self._at(self._grid, i), self._at(self._mix, i)
        value = a + (self._at(self._mix, i + 1) - a) * ((lam_c - x0) / (self._at(self._grid, i + 1) - x0))
        return self._select(inside, value, 0.0)

    def invert(self, k: int, lam):
        """F_k(lam): the u that ``sample(k, u)`` maps to lam (0 left of the grid, 1 right)."""
        lam_c = self._clip(lam, self.lo, self.hi)
        i = self._interval(self._grid, lam_c)
        pn, F = self._pn[k], self._F[k]
        x0, x1 = self._at(self._grid, i), self._at(self._grid, i + 1)
        t = lam_c - x0
        a = self._at(pn, i)
        p_lam = a + (self._at(pn, i + 1) - a) * (t / (x1 - x0))
        return self._clip(self._at(F, i) + 0.5 * t * (a + p_lam), 0.0, 1.0)

    def sample_four(self, u):
        """The four wavelengths of a path and their mixture densities, from one u.

        Returns
        -------
        lam : list of 4 Float64 (or floats), nm
            lambda_k = F_k^-1(u).
        pdf : list of 4 Float64 (or floats), 1/nm
            (1/4) sum_m p_m(lambda_k), from the segment the search found (as the header does).
        """
        u = self._clip(u, 0.0, 1.0)
        segs = self._four_segments(u)
        lam, pdf = [], []
        for k in range(N_DENSITIES):
            t, p, x0 = self._solve(k, segs[k], u)
            lam.append(x0 + t)
            pdf.append(p)
        return lam, pdf
