"""Table grids: the default 5 nm grid, and adaptive refinement for spiky lamps.

Densities are piecewise linear on the table grid (SPEC 1), so they cannot follow an
emission line narrower than a grid step: inside that step f / sum_k p_k varies with the
line's shape, and C(u) with it. On the default 5 nm grid this limits line lamps (compact
fluorescent, metal halide, sodium) to J of 15-35 % of stratified uniform sampling, while
smooth spectra reach 1 %. SPEC 2 allows any increasing grid, so the "auto" grid adds nodes
where a piecewise-linear function on the grid represents the lamp badly:

    error of segment i = integral over the segment of |q - L_i q| / integral of q,

q = I * (xbar + ybar + zbar) (the weight of the initialization) and L_i q its linear
interpolation between the segment's end nodes. Segments are halved, worst first, down to
``MIN_STEP_NM``, until the grid has a fixed number of nodes (fixed so that all refined
problems share one compiled objective).
"""

from __future__ import annotations

import heapq

import numpy as np

from .objective import DEFAULT_GRID, Problem

#: Total interpolation error of q on the default grid above which "auto" refines it.
#: On the LSPDD and CIE lamps the line lamps measure 0.17-0.44 and all others below 0.02.
SPIKY_ERROR = 0.05

#: (node count, smallest step in nm) of the refined grids tried in turn by "auto": the
#: first before optimizing, the next only if J is still above the target. Fixed counts
#: let all refined problems share compiled objectives. LSPDD spectra are sampled at
#: 0.5-1 nm.
REFINED = ((161, 1.25), (241, 0.625))

#: Segments are not split below this width by default, nm.
MIN_STEP_NM = 1.25


def _q_on(problem: Problem, lam: np.ndarray) -> np.ndarray:
    n = problem.n_nodes
    x = problem.nodes[:n]
    return np.interp(lam, x, problem.spec[:n]) * np.interp(lam, x, problem.cmf[:n].sum(axis=1))


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


def refine(problem: Problem, grid: np.ndarray, n_nodes: int, min_step: float = MIN_STEP_NM) -> np.ndarray:
    """Halve the worst segments of ``grid`` until it has ``n_nodes`` nodes.

    The segment with the largest interpolation error is split at its midpoint, the errors
    of its two halves are computed, and so on (never below ``min_step`` nm). Stops early
    if no segment can be split. The original nodes are kept, so a table on ``grid`` is
    exactly representable on the result.
    """
    g = np.asarray(grid, dtype=np.float64)
    if n_nodes <= g.size:
        return g.copy()
    total = _q_total(problem)
    errs = _abs_errors(problem, g) / total
    heap = [(-e, float(a), float(b)) for e, a, b in zip(errs, g[:-1], g[1:])]
    heapq.heapify(heap)
    new_nodes: list[float] = []
    while heap and g.size + len(new_nodes) < n_nodes:
        e, a, b = heapq.heappop(heap)
        if (b - a) / 2.0 < min_step - 1e-9 or e >= 0.0:
            continue
        m = 0.5 * (a + b)
        new_nodes.append(m)
        ea, eb = _abs_errors(problem, np.array([a, m, b])) / total
        heapq.heappush(heap, (-ea, a, m))
        heapq.heappush(heap, (-eb, m, b))
    return np.unique(np.concatenate([g, np.asarray(new_nodes)]))
