"""The u-quadrature of the estimator C(u) of a table (design §4).

For a table of four densities p_k on the grid lambda_0..lambda_M (design §1) and a path that
carries the lamp's spectrum I, the estimator of the lamp's colour is

    C(u) = sum_j f(lambda_j(u)) / sum_k p_k(lambda_j(u)),   f = I * (xbar, ybar, zbar),

with lambda_j(u) = F_j^-1(u) (one u for all four wavelengths). f is piecewise quadratic on
the union of spectrum, CMF and table nodes (``problem``), so C(u) is smooth except where
some lambda_j(u) crosses one of those nodes, i.e. at u = F_j(node). Those values are the
breakpoints in u: between two consecutive breakpoints the integrand is smooth and
Gauss-Legendre converges fast, so J computed with ``ORDER`` and ``ORDER_FINE`` points per
piece agree closely (both are reported). The breakpoints move with the densities, and J is
differentiated through them (Leibniz's rule comes out of automatic differentiation of the
quadrature).

Everything here is a pure function of (densities, ``Problem.arrays``), traced into the
jitted objective (``objective``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from . import sampling

Array = jax.Array

#: Gauss-Legendre points per piece between u-breakpoints: the resolution the solvers
#: search with and report (J), and the refined one that shows J has converged (J_fine;
#: on the reference tables the two agree to ~1e-4 relative, and order 6 adds nothing
#: visible to order 4).
ORDER = 2
ORDER_FINE = 4

#: Gauss-Legendre points per piece while the solvers search (the midpoint rule: the
#: pieces between breakpoints are short, and the tables found are judged at ``ORDER``
#: and ``ORDER_FINE``).
SEARCH_ORDER = 1


def gauss_legendre(order: int) -> tuple[Array, Array]:
    """Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(order)
    return jax.device_put(0.5 * (x + 1.0)), jax.device_put(0.5 * w)


def f_at(arr: dict, lam: Array) -> Array:
    """f(lam) = I(lam) * cmf(lam), shape lam.shape + (3,); zero outside the grid range.

    With surface colours (design §4.5) f = I R_k cmf for every colour k, shape
    (K,) + lam.shape + (3,)."""
    x = arr["nodes"]
    n = x.shape[0]
    i = jnp.clip(jnp.searchsorted(x, lam, side="right") - 1, 0, n - 2)
    w = (lam - x[i]) / (x[i + 1] - x[i])
    w = jnp.clip(w, 0.0, 1.0)
    spec = arr["spec"][..., i] * (1.0 - w) + arr["spec"][..., i + 1] * w
    cmf = arr["cmf"][i] * (1.0 - w)[..., None] + arr["cmf"][i + 1] * w[..., None]
    inside = (lam >= x[0]) & (lam <= arr["bp"][-1])
    return jnp.where(inside[..., None], spec[..., None] * cmf, 0.0)


def normalized(grid: Array, P: Array) -> tuple[Array, Array]:
    return jax.vmap(lambda p: sampling.normalized_with_cdf(grid, p))(P)


def _cdf_at_breakpoints(arr: dict, PN: Array, FF: Array) -> Array:
    """F_j(x) for every breakpoint wavelength x and density j, shape (4, Nb)."""
    grid = arr["grid"]
    seg, t = arr["bp_seg"], arr["bp_t"]
    w = t / (grid[seg + 1] - grid[seg])

    def one(pn, F):
        p_x = pn[seg] * (1.0 - w) + pn[seg + 1] * w
        return jnp.clip(F[seg] + 0.5 * t * (pn[seg] + p_x), 0.0, 1.0)

    return jax.vmap(one)(PN, FF)


def pieces(breaks: Array, glx: Array, glw: Array) -> tuple[Array, Array]:
    """Gauss-Legendre points and weights on every interval between sorted breakpoints."""
    b = jnp.sort(jnp.concatenate([jnp.zeros(1), breaks.ravel(), jnp.ones(1)]))
    a, width = b[:-1], b[1:] - b[:-1]
    u = (a[:, None] + width[:, None] * glx[None, :]).ravel()
    wt = (width[:, None] * glw[None, :]).ravel()
    return u, wt


def _mixture_at(PN: Array, seg: Array, w: Array) -> Array:
    """sum_k p_k(lambda_j) for wavelengths at relative position w in table segment seg:
    every density is linear on the segment lambda_j fell into."""
    return jnp.sum(PN[:, seg] * (1.0 - w)[None] + PN[:, seg + 1] * w[None], axis=0)


def _balance_ratio(f: Array, msum: Array) -> Array:
    """The balance heuristic's terms f(lambda_j) / sum_k p_k(lambda_j); 0 where the mixture
    is 0 (no density samples there: f is 0 there too on a table without bias)."""
    pos = msum > 0
    return jnp.where(pos[..., None], f / jnp.where(pos, msum, 1.0)[..., None], 0.0)


def table_estimate(arr: dict, PN: Array, FF: Array, u: Array) -> Array:
    """C(u) for normalized densities PN with CDFs FF, shape u.shape + (3,)."""
    grid = arr["grid"]
    seg, t = jax.vmap(lambda pn, F: sampling.sample_segment(grid, pn, F, u))(PN, FF)
    lam = grid[seg] + t  # (4, n)
    w = t / (grid[seg + 1] - grid[seg])
    f = f_at(arr, lam)  # ([K,] 4, n, 3)
    return jnp.sum(_balance_ratio(f, _mixture_at(PN, seg, w)), axis=-3)


def table_quadrature(P: Array, arr: dict, glx: Array, glw: Array):
    """Points u, weights, C(u) and sum_j (f_j / M_j)^2 of the piecewise Gauss-Legendre rule
    for table P (with surface colours, C and the squares per colour).

    The breakpoints F_j(node) of all four densities are sorted together; a running
    maximum over the sorted list tells, for every piece, the node interval each
    lambda_j(u) lies in (and hence its table segment), so no search is needed per point.
    """
    grid = arr["grid"]
    x = arr["nodes"]
    nd = sampling.N_DENSITIES
    PN, FF = normalized(grid, P)
    Fb = _cdf_at_breakpoints(arr, PN, FF)  # (4, Nb)
    nb = Fb.shape[1]
    # The strata's edges of the ``stratified`` objective (design §4.6) join as breakpoints
    # of no density (label nd): every piece then lies in one stratum.
    flat = jnp.concatenate([Fb.ravel(), arr["strata"]]) if "strata" in arr else Fb.ravel()
    order = jnp.argsort(flat, stable=True)
    b = flat[order]
    lab_j = order // nb
    lab_n = arr["bp_idx"][order % nb]
    own = lab_j[None, :] == jnp.arange(nd)[:, None]
    cur = jax.lax.cummax(jnp.where(own, lab_n[None, :], -1), axis=1)[:, :-1]
    # (4, K-1): node interval of lambda_j on every piece. A density whose CDF reaches 1 at
    # its last node before the others do (a zero tail) would name that node on the pieces
    # after it (of width ~0): they lie in the last interval.
    cur = jnp.clip(cur, 0, x.shape[0] - 2)
    width = b[1:] - b[:-1]
    u = b[:-1, None] + width[:, None] * glx[None, :]  # (K-1, g)
    wt = (width[:, None] * glw[None, :]).ravel()
    u = u.ravel()
    g = glx.shape[0]
    node = jnp.repeat(cur, g, axis=1)  # (4, n)
    seg = arr["node_tseg"][node]
    t = jax.vmap(lambda pn, F, i: sampling.solve_in_segment(grid, pn, F, i, u))(PN, FF, seg)
    lam = grid[seg] + t
    # f on the node interval, the mixture on the table segment.
    wn = jnp.clip((lam - x[node]) / (x[node + 1] - x[node]), 0.0, 1.0)
    if arr["spec"].ndim == 1:
        # One white surface: exactly the operations (and order) the solvers were tuned on;
        # a reordering changes the gradient's rounding, and on hard lamps that moves the
        # optimum found.
        spec = arr["spec"][node] * (1.0 - wn) + arr["spec"][node + 1] * wn
        cmf = arr["cmf"][node] * (1.0 - wn)[..., None] + arr["cmf"][node + 1] * wn[..., None]
        f = spec[..., None] * cmf  # (4, n, 3)
        w = t / (grid[seg + 1] - grid[seg])
        ratio = _balance_ratio(f, _mixture_at(PN, seg, w))
        return u, wt, jnp.sum(ratio, axis=0), jnp.sum(ratio * ratio, axis=0)
    cmf = arr["cmf"][node] * (1.0 - wn)[..., None] + arr["cmf"][node + 1] * wn[..., None]
    w = t / (grid[seg + 1] - grid[seg])
    msum = _mixture_at(PN, seg, w)

    # Surface colours (design §4.5): everything above is shared; only f differs per colour.
    def terms(spec_nodes):
        spec = spec_nodes[node] * (1.0 - wn) + spec_nodes[node + 1] * wn
        f = spec[..., None] * cmf  # (4, n, 3)
        ratio = _balance_ratio(f, msum)
        return jnp.sum(ratio, axis=0), jnp.sum(ratio * ratio, axis=0)

    C, D = jax.vmap(terms)(arr["spec"])
    return u, wt, C, D
