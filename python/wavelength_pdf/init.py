"""The published method's starting point: an equal-mass partition of the spectrum.

The method's publication (Dobos 2025, "Perception-based Optimization of Wavelength Sampling
Distributions for Spectral Rendering", TU Delft, eq. 15-17; its 4 x 81 tables were made from
it) starts the optimizer from four densities that split
the spectrum into four parts of equal mass:

    q(lambda) = I(lambda) * (xbar + ybar + zbar)(lambda),      Q = integral of q,
    a_0 = lambda_0, a_4 = lambda_M, a_k = the k/4 quantile of q  (equal mass 1/4 each),
    p_k = q restricted to [a_k, a_{k+1}], normalized.

Two choices are made here where that description meets a table grid:

- The weight is the spectrum times the *sum* of the three CMFs (as in Dobos 2025),
  not the luminance alone, so that blue light that Y barely sees still gets samples.
- A node value is the hat-function average of q over the node's two neighbouring segments
  (restricted to [a_k, a_{k+1}]), not q sampled at the node. For smooth spectra both are
  the same to first order; for an emission line that falls between two nodes (a 2 nm line
  while the grid has 5 nm steps, so q is zero at every node) sampling q at the nodes would
  give an all-zero density, while the average puts the line's mass on the two nodes around
  it. The same average makes the mixture positive at both ends of every segment where
  f = I * cmf is positive, so the initialization is unbiased by construction.
"""

from __future__ import annotations

import numpy as np

from .model import normalize_density, trapezoid
from .problem import Problem
from .sampling import N_DENSITIES

#: Gauss-Legendre rule exact for the cubic q * hat on each piece.
_GL2_X = 0.5 * (1.0 + np.array([-1.0, 1.0]) / np.sqrt(3.0))


def _q_pieces(problem: Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Union nodes and the end values of the two linear factors of q on every segment."""
    n = problem.n_nodes
    x = problem.nodes[:n]
    s = problem.spec[:n]
    w = problem.cmf[:n].sum(axis=1)
    return x, s, w


def _cumulative_q(x: np.ndarray, s: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Exact cumulative integral of q = s * w (both linear per segment) at the nodes."""
    h = np.diff(x)
    seg = h * (s[:-1] * w[:-1] + 4.0 * 0.25 * (s[:-1] + s[1:]) * (w[:-1] + w[1:]) + s[1:] * w[1:]) / 6.0
    return np.concatenate([[0.0], np.cumsum(seg)])


def _q_partial(x0, h, s0, s1, w0, w1, t):
    """Integral of q from x0 to x0 + t on a segment of width h (q = linear * linear)."""
    ds = (s1 - s0) / h
    dw = (w1 - w0) / h
    return s0 * w0 * t + 0.5 * (s0 * dw + w0 * ds) * t**2 + ds * dw * t**3 / 3.0


def mass_cuts(problem: Problem, n: int) -> np.ndarray:
    """Wavelengths a_0 < ... < a_n (nm) that split q into n parts of equal mass."""
    x, s, w = _q_pieces(problem)
    Q = _cumulative_q(x, s, w)
    total = Q[-1]
    cuts = [x[0]]
    for k in range(1, n):
        target = total * k / n
        i = int(np.clip(np.searchsorted(Q, target, side="right") - 1, 0, x.size - 2))
        h = x[i + 1] - x[i]
        lo, hi = 0.0, h
        # The partial integral is monotone in t: bisection to float64 resolution.
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if Q[i] + _q_partial(x[i], h, s[i], s[i + 1], w[i], w[i + 1], mid) < target:
                lo = mid
            else:
                hi = mid
        cuts.append(x[i] + 0.5 * (lo + hi))
    cuts.append(x[-1])
    return np.maximum.accumulate(np.asarray(cuts))


def equal_mass_cuts(problem: Problem) -> np.ndarray:
    """Wavelengths a_0 < ... < a_4 (nm) that split q into four parts of equal mass."""
    return mass_cuts(problem, N_DENSITIES)


def hat_parts(problem: Problem, cuts: np.ndarray, grid: np.ndarray | None = None) -> np.ndarray:
    """Hat-function averages of q restricted to each part [cuts[i], cuts[i+1]].

    ``grid`` (default: the problem's table grid) gives the nodes; any increasing grid
    over the same range works (the multi-level solver uses coarser ones).

    Returns
    -------
    (len(cuts) - 1, M+1) array
        Row i holds, at every table node, the integral of q times the node's hat function
        over part i, divided by the integral of the hat function. The rows add up to the
        hat average of q, and the trapezoid rule of row i is exactly the mass of part i.
    """
    grid = problem.grid if grid is None else np.asarray(grid, dtype=np.float64)
    x, s, w = _q_pieces(problem)
    # Pieces on which q * hat is a cubic: union nodes, grid nodes and the cuts.
    r = np.unique(np.concatenate([x, grid, cuts]))
    a, b = r[:-1], r[1:]
    h = b - a
    lam = a[:, None] + h[:, None] * _GL2_X[None, :]  # (pieces, 2)
    q = np.interp(lam, x, s) * np.interp(lam, x, w)
    wt = 0.5 * h[:, None] * np.ones(2)[None, :]
    # Table segment of each piece, the two hat functions on it, and the piece's part.
    m = grid.size - 1
    mid = 0.5 * (a + b)
    seg = np.clip(np.searchsorted(grid, mid, side="right") - 1, 0, m - 1)
    frac = (lam - grid[seg][:, None]) / (grid[seg + 1] - grid[seg])[:, None]
    n_parts = len(cuts) - 1
    part = np.clip(np.searchsorted(cuts, mid, side="right") - 1, 0, n_parts - 1)
    V = np.zeros((n_parts, grid.size))
    np.add.at(V, (part, seg), np.sum(wt * q * (1.0 - frac), axis=1))
    np.add.at(V, (part, seg + 1), np.sum(wt * q * frac, axis=1))
    # Hat average: divide by the integral of each hat function.
    hw = np.diff(grid)
    hat_int = 0.5 * (np.concatenate([[0.0], hw]) + np.concatenate([hw, [0.0]]))
    return V / hat_int[None, :]


def _normalize_rows(problem: Problem, V: np.ndarray, grid: np.ndarray | None = None) -> np.ndarray:
    grid = problem.grid if grid is None else grid
    if not np.all(trapezoid(grid, V) > 0):
        raise ValueError(f"{problem.source}: the spectrum has no mass to partition")
    return normalize_density(grid, V)


def equal_mass_partition(problem: Problem, grid: np.ndarray | None = None) -> np.ndarray:
    """The four initial densities (4, M+1), each normalized by the trapezoid rule.

    Raises
    ------
    ValueError
        If q is zero everywhere (the problem builder already rejects such spectra).
    """
    return _normalize_rows(problem, hat_parts(problem, equal_mass_cuts(problem), grid), grid)


def support_density(problem: Problem, grid: np.ndarray | None = None) -> np.ndarray:
    """The mixture of the equal-mass densities, (M+1,), normalized.

    It is positive at both ends of every table segment where f > 0, and proportional to
    the local average of q: the defensive component the solvers mix into every density.
    """
    return np.mean(equal_mass_partition(problem, grid), axis=0)


def support_nodes(problem: Problem, grid: np.ndarray | None = None) -> np.ndarray:
    """Boolean (M+1,): nodes that touch a table segment where f = I * cmf is positive."""
    return support_density(problem, grid) > 0


# --- Further starting points for the multi-start solver ------------------------------


def overlapping_partition(problem: Problem, parts: int = 7, grid: np.ndarray | None = None) -> np.ndarray:
    """Cut q into ``parts`` equal-mass parts; density k covers parts k .. k + parts - 4.

    Neighbouring densities overlap, which suits smooth spectra (broad densities whose
    wavelengths sweep their range together as u grows).
    """
    if parts < N_DENSITIES:
        raise ValueError("parts must be >= 4")
    H = hat_parts(problem, mass_cuts(problem, parts), grid)
    width = parts - N_DENSITIES + 1
    return _normalize_rows(problem, np.stack([H[k : k + width].sum(axis=0) for k in range(N_DENSITIES)]), grid)


def range_quarters(problem: Problem, grid: np.ndarray | None = None) -> np.ndarray:
    """Density k uniform on the k-th quarter of the grid range (restricted to the support,
    one node of overlap), the table analogue of stratified uniform sampling."""
    g = problem.grid if grid is None else np.asarray(grid, dtype=np.float64)
    lo, hi = g[0], g[-1]
    support = support_nodes(problem, g)
    V = np.zeros((N_DENSITIES, g.size))
    edges = lo + (hi - lo) * np.arange(N_DENSITIES + 1) / N_DENSITIES
    for k in range(N_DENSITIES):
        i0 = max(int(np.searchsorted(g, edges[k], side="right")) - 2, 0)
        i1 = min(int(np.searchsorted(g, edges[k + 1], side="left")) + 1, g.size - 1)
        V[k, i0 : i1 + 1] = 1.0
    V = V * support[None, :]
    # A quarter without support (a line lamp) falls back to the support density.
    empty = ~np.any(V > 0, axis=1)
    V[empty] = support_density(problem, g)[None, :]
    return _normalize_rows(problem, V, g)


def range_windows(problem: Problem, grid: np.ndarray | None = None) -> np.ndarray:
    """Density k uniform on [lo + k w, lo + (k + 2) w], w = (hi - lo) / 5: four windows
    of 2/5 of the range, each overlapping its neighbours by half (restricted to the
    support)."""
    g = problem.grid if grid is None else np.asarray(grid, dtype=np.float64)
    lo, hi = g[0], g[-1]
    support = support_nodes(problem, g)
    w = (hi - lo) / (N_DENSITIES + 1)
    V = np.stack([((g >= lo + k * w - 1e-9) & (g <= lo + (k + 2) * w + 1e-9)).astype(float)
                  for k in range(N_DENSITIES)]) * support[None, :]
    empty = ~np.any(V > 0, axis=1)
    V[empty] = support_density(problem, g)[None, :]
    return _normalize_rows(problem, V, g)


def random_bumps(problem: Problem, rng: np.random.Generator, grid: np.ndarray | None = None) -> np.ndarray:
    """Four broad Gaussian bumps at random places (restricted to the support)."""
    g = problem.grid if grid is None else np.asarray(grid, dtype=np.float64)
    lo, hi = g[0], g[-1]
    support = support_nodes(problem, g)
    V = np.zeros((N_DENSITIES, g.size))
    for k in range(N_DENSITIES):
        centre = rng.uniform(lo, hi)
        width = rng.uniform(0.05, 0.4) * (hi - lo)
        V[k] = np.exp(-0.5 * ((g - centre) / width) ** 2) + 1e-3
    return _normalize_rows(problem, V * support[None, :], g)


def starting_points(problem: Problem, seed: int = 0, n_random: int = 2,
                    grid: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Named starting tables for a multi-start solver, deterministic for a seed.

    The published equal-mass partition comes first; the others are found (on the
    reference lamps) to lead to better local optima for smooth spectra.
    """
    rng = np.random.default_rng(seed)
    out = {
        "equal-mass": equal_mass_partition(problem, grid),
        "quarters": range_quarters(problem, grid),
        "overlap": overlapping_partition(problem, 7, grid),
        "windows": range_windows(problem, grid),
    }
    for i in range(n_random):
        out[f"random{i}"] = random_bumps(problem, rng, grid)
    return out
