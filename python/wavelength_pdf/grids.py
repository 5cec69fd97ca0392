"""Table grids: the default 5 nm grid, and grids that resolve emission lines of any width.

Densities are piecewise linear on the table grid (design §1), so they cannot follow an
emission line narrower than a grid step: inside that step f / sum_k p_k varies with the
line's shape, and C(u) with it. A 0.2 nm laser line on the 5 nm grid stays at ~0.4 x
stratified uniform J. design §2 allows any increasing grid, so the "auto" grid adds nodes
where a piecewise-linear function on the grid represents the lamp badly:

    error of segment i = integral over the segment of |q - L_i q| / integral of q,

q = I * (xbar + ybar + zbar) (the weight of the initialization) and L_i q its linear
interpolation between the segment's end nodes. The worst segment is split first, at the
point where q departs most from the segment's chord, chosen among the spectrum's own
breakpoints (Ramer-Douglas-Peucker; the midpoint if that is further off): a line gets
nodes at its peak and at its edges, however narrow it is, down to ``MIN_STEP_NM``.
Splitting stops when the error is below ``TARGET_ERROR`` or the node budget is spent; the
grid is then filled up (midpoints of the widest segments) to the next of ``BUCKETS``, so
that all refined problems share a few compiled objectives.

What the nodes cost: the renderer finds a wavelength's segment by binary search
(log2 of the node count: 9 steps for 481 nodes against 7 for 81), and the optimizer's work
per evaluation grows with the union of spectrum, CMF and table nodes (the CMFs alone
bring 401).
"""

from __future__ import annotations

import heapq

import numpy as np

from .model import DEFAULT_GRID
from .problem import Problem

#: Total interpolation error of q on the default grid above which "auto" refines it.
#: The LSPDD line lamps measure 0.17-0.44; of colour-science's spectra (5 nm lists, so
#: q is nearly linear between 5 nm nodes) the mercury lamps measure 0.013-0.015 and reach
#: 0.05 x uniform J only when refined (0.052 -> 0.017), the fluorescent and LED lamps
#: at most 0.0126, daylight and incandescent spectra less.
SPIKY_ERROR = 0.012

#: "auto" refines until the total interpolation error of q is below this.
TARGET_ERROR = 0.003

#: Node counts of refined grids: a refined grid is filled up to the next one (fixed
#: shapes let problems share compiled objectives); the last is the node budget.
BUCKETS = (161, 241, 321, 481)

#: Segments are not split below this width, nm (the narrowest lines that matter for
#: lamps and lasers are ~0.1 nm wide).
MIN_STEP_NM = 0.05


def _q_on(problem: Problem, lam: np.ndarray) -> np.ndarray:
    n = problem.n_nodes
    x = problem.nodes[:n]
    return np.interp(lam, x, problem.spec[:n]) * np.interp(lam, x, problem.cmf[:n].sum(axis=1))


class _Q:
    """q sampled where it is exactly known to second order: the problem's nodes and
    their midpoints (q is the product of two functions linear between nodes)."""

    def __init__(self, problem: Problem):
        x = problem.nodes[: problem.n_nodes]
        self.knots = x
        self.x = np.unique(np.concatenate([x, 0.5 * (x[1:] + x[:-1])]))
        self.q = _q_on(problem, self.x)
        self.problem = problem
        self.total = float(np.sum(0.5 * (self.q[1:] + self.q[:-1]) * np.diff(self.x)))

    def inside(self, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
        """Sample points in [a, b] (ends included) and q there."""
        i0 = int(np.searchsorted(self.x, a, side="right"))
        i1 = int(np.searchsorted(self.x, b, side="left"))
        xs = np.concatenate([[a], self.x[i0:i1], [b]])
        qs = np.concatenate([_q_on(self.problem, np.array([a])), self.q[i0:i1],
                             _q_on(self.problem, np.array([b]))])
        return xs, qs

    def error(self, a: float, b: float) -> float:
        """Integral over [a, b] of |q - chord| (unnormalized)."""
        xs, qs = self.inside(a, b)
        d = np.abs(qs - (qs[0] + (qs[-1] - qs[0]) * (xs - a) / (b - a)))
        return float(np.sum(0.5 * (d[1:] + d[:-1]) * np.diff(xs)))

    def split_point(self, a: float, b: float, min_step: float) -> float | None:
        """Where to split [a, b]: the breakpoint of q furthest from the chord (at least
        ``min_step`` from both ends), or the midpoint if that is further; None if the
        segment is too narrow to split."""
        if (b - a) < 2.0 * min_step - 1e-12:
            return None
        xs, qs = self.inside(a, b)
        ok = (xs >= a + min_step - 1e-12) & (xs <= b - min_step + 1e-12)
        m = 0.5 * (a + b)
        chord = qs[0] + (qs[-1] - qs[0]) * (xs - a) / (b - a)
        dev = np.where(ok, np.abs(qs - chord), -1.0)
        i = int(np.argmax(dev))
        qm = float(_q_on(self.problem, np.array([m]))[0])
        dm = abs(qm - (qs[0] + 0.5 * (qs[-1] - qs[0])))
        return float(xs[i]) if dev[i] > dm else m


def _abs_errors(problem: Problem, grid: np.ndarray) -> np.ndarray:
    """Per segment of ``grid``: integral of |q - linear interpolation of q| (unnormalized).

    Evaluated on the problem's nodes inside the grid's range and their midpoints (q is
    the product of two functions linear between the problem's nodes).
    """
    grid = np.asarray(grid, dtype=np.float64)
    x = problem.nodes[: problem.n_nodes]
    xx = np.unique(np.concatenate([x, 0.5 * (x[1:] + x[:-1]), grid]))
    xx = xx[(xx >= grid[0]) & (xx <= grid[-1])]
    d = np.abs(_q_on(problem, xx) - np.interp(xx, grid, _q_on(problem, grid)))
    mid = 0.5 * (xx[1:] + xx[:-1])
    seg = np.clip(np.searchsorted(grid, mid, side="right") - 1, 0, grid.size - 2)
    return np.bincount(seg, weights=0.5 * (d[1:] + d[:-1]) * np.diff(xx), minlength=grid.size - 1)


def _q_total(problem: Problem) -> float:
    x = problem.nodes[: problem.n_nodes]
    xx = np.unique(np.concatenate([x, 0.5 * (x[1:] + x[:-1])]))
    q = _q_on(problem, xx)
    return float(np.sum(0.5 * (q[1:] + q[:-1]) * np.diff(xx)))


def segment_errors(problem: Problem, grid: np.ndarray) -> np.ndarray:
    """Per segment of ``grid``: integral of |q - linear interpolation of q| / integral of q."""
    return _abs_errors(problem, grid) / _q_total(problem)


def interpolation_error(problem: Problem, grid: np.ndarray) -> float:
    """Total relative error of representing q piecewise linearly on ``grid``."""
    return float(np.sum(segment_errors(problem, grid)))


def is_spiky(problem: Problem, grid: np.ndarray = DEFAULT_GRID) -> bool:
    """True if the lamp has structure that ``grid`` cannot follow (line lamps)."""
    return interpolation_error(problem, grid) > SPIKY_ERROR


def refine(problem: Problem, grid: np.ndarray, n_nodes: int, min_step: float = MIN_STEP_NM,
           target_error: float = 0.0) -> np.ndarray:
    """Split the worst segments of ``grid`` until it has ``n_nodes`` nodes.

    The segment with the largest interpolation error is split (at ``_Q.split_point``:
    the spectrum's breakpoint furthest from the segment's chord, so lines get nodes at
    their edges and peak), the errors of its two parts are computed, and so on, never
    below ``min_step`` nm. Stops early when the total error of the segments that can
    still be split falls below ``target_error``, or none can. The original nodes are kept, so a table
    on ``grid`` is exactly representable on the result.
    """
    g = np.asarray(grid, dtype=np.float64)
    if n_nodes <= g.size:
        return g.copy()
    Q = _Q(problem)
    if not Q.total > 0:
        return g.copy()
    errs = [Q.error(a, b) / Q.total for a, b in zip(g[:-1], g[1:])]
    total = float(np.sum(errs))
    heap = [(-e, float(a), float(b)) for e, a, b in zip(errs, g[:-1], g[1:])]
    heapq.heapify(heap)
    new_nodes: list[float] = []
    while heap and g.size + len(new_nodes) < n_nodes and total > target_error:
        e, a, b = heapq.heappop(heap)
        if e >= 0.0:
            break
        m = Q.split_point(a, b, min_step)
        if m is None:
            total += e  # out of reach: no longer counts against the target
            continue
        new_nodes.append(m)
        ea, eb = Q.error(a, m) / Q.total, Q.error(m, b) / Q.total
        total += ea + eb + e
        heapq.heappush(heap, (-ea, a, m))
        heapq.heappush(heap, (-eb, m, b))
    return np.unique(np.concatenate([g, np.asarray(new_nodes)]))


def fill_to(grid: np.ndarray, n_nodes: int) -> np.ndarray:
    """Add midpoints of the widest segments until ``grid`` has ``n_nodes`` nodes."""
    g = np.asarray(grid, dtype=np.float64)
    heap = [(-(b - a), float(a), float(b)) for a, b in zip(g[:-1], g[1:])]
    heapq.heapify(heap)
    new_nodes: list[float] = []
    while heap and g.size + len(new_nodes) < n_nodes:
        w, a, b = heapq.heappop(heap)
        m = 0.5 * (a + b)
        new_nodes.append(m)
        heapq.heappush(heap, (-(m - a), a, m))
        heapq.heappush(heap, (-(b - m), m, b))
    return np.unique(np.concatenate([g, np.asarray(new_nodes)]))


def bucket(n: int) -> int:
    """The smallest of ``BUCKETS`` that holds ``n`` nodes (the last one at most)."""
    for b in BUCKETS:
        if n <= b:
            return b
    return BUCKETS[-1]


def auto_grid(problem: Problem, base: np.ndarray = DEFAULT_GRID) -> np.ndarray:
    """The "auto" table grid for ``problem``: ``base`` for smooth spectra; for line lamps
    ``base`` refined around the lines (to ``TARGET_ERROR``, within the node budget
    ``BUCKETS[-1]``) and filled up to a bucketed node count."""
    base = np.asarray(base, dtype=np.float64)
    if not is_spiky(problem, base):
        return base.copy()
    g = refine(problem, base, BUCKETS[-1], MIN_STEP_NM, TARGET_ERROR)
    return fill_to(g, bucket(g.size))
