"""The wavelength sampling model shared by the optimizer and the renderer (design §1).

A table holds four densities p_0..p_3 over one strictly increasing grid of nodes
lambda_0 < ... < lambda_M [nm]. Each density is piecewise *linear* between its node values,
zero outside [lambda_0, lambda_M], and normalized so that the trapezoid rule integrates it
to 1. Its CDF F is therefore piecewise quadratic, and a wavelength is drawn exactly as
lambda = F^-1(u) by solving one quadratic inside the segment that holds u. All four
wavelengths of a path share the same u; the estimator divides by the mixture
(1/4) sum_k p_k, i.e. it is the balance heuristic over the four densities.

Every routine comes as a sample / pdf / invert triple. The functions are pure jax.numpy, so
they are differentiable with respect to the density values (and to u), can be jitted, and
accept NumPy float64 input (the package enables jax x64).

The baseline "stratified uniform" sampler of design §4
(lambda_j = lo + (hi - lo) * ((u + j/4) mod 1)) is not a piecewise-linear table; it is
given here as its own triple so that every sampler of the project lives in one file.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

Array = jax.Array

from .model import N_DENSITIES  # noqa: E402  (wavelengths per path; design §1)
from . import model as _model  # noqa: E402


def _segment_widths(grid: Array) -> Array:
    return grid[1:] - grid[:-1]


def normalize(grid: Array, p: Array) -> Array:
    """Scale node values so that the piecewise-linear density integrates to 1
    (``model.normalize_density`` in jax.numpy, so that it can be traced).

    Parameters
    ----------
    grid : (M+1,) array, nm
        Strictly increasing nodes.
    p : (M+1,) array, >= 0
        Density values at the nodes (any positive scale).

    Returns
    -------
    (M+1,) array, 1/nm
        ``p / trapezoid(p, grid)``. The caller must not pass a density that is zero
        everywhere (the table readers reject it).
    """
    return _model.normalize_density(jnp.asarray(grid), jnp.asarray(p), xp=jnp)


def _normalized_with_cdf(grid: Array, p: Array) -> tuple[Array, Array]:
    """Normalized node values and the CDF at the nodes (F[0] = 0, F[M] = 1 exactly)."""
    return _model.normalized_with_cdf(jnp.asarray(grid), jnp.asarray(p), xp=jnp)


def cdf(grid: Array, p: Array) -> Array:
    """CDF of the normalized piecewise-linear density at the grid nodes.

    Returns
    -------
    (M+1,) array
        F(lambda_i), with F[0] = 0 and F[M] = 1.
    """
    return _normalized_with_cdf(grid, p)[1]


def _last_segment_with_mass(pn: Array) -> Array:
    """Index of the last segment whose density is not zero at both ends.

    Judged from the node values, not from CDF differences, which rounding can make an ulp
    positive on a segment without probability.
    """
    has_mass = (pn[1:] + pn[:-1]) > 0
    m = has_mass.shape[0]
    return m - 1 - jnp.argmax(has_mass[::-1])


def normalized_with_cdf(grid: Array, p: Array) -> tuple[Array, Array]:
    """Normalized node values and the CDF at the nodes (F[0] = 0, F[M] = 1 exactly).

    Returns
    -------
    pn : (M+1,) array, 1/nm
    F : (M+1,) array
    """
    return _normalized_with_cdf(grid, p)


def sample_segment(grid: Array, pn: Array, F: Array, u: Array) -> tuple[Array, Array]:
    """Segment index and offset of lambda = F^-1(u) for an already normalized density.

    Inside segment i (width h, node values p0, p1, slope s = (p1 - p0) / h) the CDF is
    F_i + p0 t + s t^2 / 2, so the offset t solves s t^2 / 2 + p0 t - r = 0 with
    r = u - F_i. The root is taken in the form t = 2 r / (p0 + sqrt(p0^2 + 2 s r)), which
    has no cancellation (both terms of the denominator are >= 0), tends to r / p0 when
    s -> 0 and to sqrt(2 r / s) when p0 = 0. Segments without probability (density zero
    at both ends) are never selected.

    Parameters
    ----------
    grid : (M+1,) array, nm
    pn, F : (M+1,) arrays
        Output of ``normalized_with_cdf``.
    u : array in [0, 1]

    Returns
    -------
    i : int array, same shape as ``u``
        Segment [grid[i], grid[i+1]] that holds the wavelength.
    t : array, same shape as ``u``, nm
        Offset from grid[i], in [0, grid[i+1] - grid[i]].
    """
    u = jnp.clip(jnp.asarray(u), 0.0, 1.0)
    # Largest i with F_i <= u skips zero-probability segments on the left of u ...
    i = jnp.searchsorted(F, u, side="right") - 1
    # ... and u = 1 must not land in a zero-probability tail.
    i = jnp.clip(i, 0, _last_segment_with_mass(pn))
    return i, solve_in_segment(grid, pn, F, i, u)


def _stable_root(a: Array, s: Array, r: Array) -> Array:
    """The root t >= 0 of s t^2 / 2 + a t = r (a >= 0, r >= 0) as 2 r / (a + sqrt(a^2 + 2 s r)).

    Both terms of the denominator are >= 0, so nothing cancels; guarded square root and
    division keep NaN out of gradients of the unselected branch (the double-where idiom).
    """
    disc = a * a + 2.0 * s * r
    disc_pos = disc > 0
    root = jnp.where(disc_pos, jnp.sqrt(jnp.where(disc_pos, disc, 1.0)), 0.0)
    den = a + root
    den_pos = den > 0
    return jnp.where(den_pos, 2.0 * r / jnp.where(den_pos, den, 1.0), 0.0)


def solve_in_segment(grid: Array, pn: Array, F: Array, i: Array, u: Array) -> Array:
    """Offset t (nm) from grid[i] at which the CDF reaches u, for u in [F_i, F_{i+1}].

    The stable quadratic solve of ``sample_segment`` for a segment that is already known
    (the objective knows it from the order of its u-breakpoints). On a falling segment the
    quadratic is solved from the right end (mass F_{i+1} - u, density p1 - s tau at
    distance tau to the left): the end where the density is smaller is where the inverse
    is ill-conditioned, and measuring from it makes u = F_{i+1} land exactly on the node.
    """
    h = grid[i + 1] - grid[i]
    p0 = pn[i]
    p1 = pn[i + 1]
    s = (p1 - p0) / h
    t_left = _stable_root(p0, s, jnp.maximum(u - F[i], 0.0))
    tau = _stable_root(p1, -s, jnp.maximum(F[i + 1] - u, 0.0))
    t = jnp.where(p1 < p0, h - tau, t_left)
    return jnp.clip(t, 0.0, h)


def sample(grid: Array, p: Array, u: Array) -> Array:
    """Draw wavelengths lambda = F^-1(u) exactly from one piecewise-linear density.

    The quadratic of each segment is solved in a cancellation-free form (see
    ``sample_segment``); zero-probability segments are never selected.

    Parameters
    ----------
    grid : (M+1,) array, nm
    p : (M+1,) array, >= 0, not all zero
    u : array of any shape, in [0, 1]

    Returns
    -------
    array, same shape as ``u``, nm
        u = 0 maps to the left end of the support and u = 1 to its right end.
    """
    grid = jnp.asarray(grid)
    pn, F = _normalized_with_cdf(grid, p)
    i, t = sample_segment(grid, pn, F, u)
    return grid[i] + t


def pdf(grid: Array, p: Array, lam: Array) -> Array:
    """Value of the normalized piecewise-linear density at wavelengths ``lam`` [1/nm].

    Zero outside [grid[0], grid[-1]].
    """
    grid = jnp.asarray(grid)
    pn = normalize(grid, p)
    return jnp.interp(jnp.asarray(lam), grid, pn, left=0.0, right=0.0)


def invert(grid: Array, p: Array, lam: Array) -> Array:
    """CDF F(lam): the u that ``sample`` maps to ``lam`` (where the density is positive).

    Within a segment F(lam) = F_i + t (p(lambda_i) + p(lam)) / 2, the exact area of the
    trapezoid under the linear density. 0 left of the grid, 1 right of it.
    """
    grid = jnp.asarray(grid)
    lam = jnp.asarray(lam)
    pn, F = _normalized_with_cdf(grid, p)
    m = grid.shape[0] - 1
    lam_c = jnp.clip(lam, grid[0], grid[-1])
    i = jnp.clip(jnp.searchsorted(grid, lam_c, side="right") - 1, 0, m - 1)
    t = lam_c - grid[i]
    h = grid[i + 1] - grid[i]
    p_lam = pn[i] + (pn[i + 1] - pn[i]) * (t / h)
    return jnp.clip(F[i] + 0.5 * t * (pn[i] + p_lam), 0.0, 1.0)


def sample_four(grid: Array, P: Array, u: Array) -> Array:
    """The four wavelengths of each path: lambda_k = F_k^-1(u), one u per path.

    Parameters
    ----------
    grid : (M+1,) array, nm
    P : (4, M+1) array
        The four densities (any positive scale each).
    u : (n,) array in [0, 1]

    Returns
    -------
    (4, n) array, nm
    """
    P = jnp.asarray(P)
    return jax.vmap(lambda pk: sample(grid, pk, u))(P)


def mixture_pdf(grid: Array, P: Array, lam: Array) -> Array:
    """Mixture density (1/4) sum_k p_k(lam) [1/nm]; the estimator's "pdf" per wavelength.

    ``lam`` may have any shape; the result has the same shape.
    """
    P = jnp.asarray(P)
    return jnp.mean(jax.vmap(lambda pk: pdf(grid, pk, lam))(P), axis=0)


def balance_estimate_weights(grid: Array, P: Array, lam: Array) -> Array:
    """1 / sum_k p_k(lam): the factor by which f(lam) is multiplied in the estimator.

    C(u) = sum_j f(lambda_j) * w(lambda_j), w = 1 / sum_k p_k (design §1).
    """
    return 1.0 / (N_DENSITIES * mixture_pdf(grid, P, lam))


# --- Stratified uniform sampling (the baseline of design §4) -------------------------


def sample_stratified_uniform(lo: float, hi: float, u: Array) -> Array:
    """lambda_j = lo + (hi - lo) * ((u + j/4) mod 1), j = 0..3 [nm], shape (4, *u.shape)."""
    u = jnp.asarray(u)
    j = jnp.arange(N_DENSITIES, dtype=u.dtype).reshape((N_DENSITIES,) + (1,) * u.ndim)
    return lo + (hi - lo) * jnp.mod(u[None] + j / N_DENSITIES, 1.0)


def pdf_stratified_uniform(lo: float, hi: float, lam: Array) -> Array:
    """Marginal density of each stratified-uniform wavelength: 1/(hi - lo) on [lo, hi]."""
    lam = jnp.asarray(lam)
    inside = (lam >= lo) & (lam <= hi)
    return jnp.where(inside, 1.0 / (hi - lo), 0.0)


def invert_stratified_uniform(lo: float, hi: float, lam: Array, j: int = 0) -> Array:
    """The u in [0, 1) for which wavelength number ``j`` equals ``lam``."""
    lam = jnp.asarray(lam)
    x = (jnp.clip(lam, lo, hi) - lo) / (hi - lo)
    return jnp.mod(x - j / N_DENSITIES, 1.0)


def stratified_uniform_table(grid: Array) -> Array:
    """Four identical uniform densities on ``grid``, shape (4, M+1).

    With the balance heuristic their estimator is (hi - lo)/4 * sum_j f(lambda_j), the
    stratified-uniform estimator; the two differ only in how the four wavelengths are
    correlated (a shared u here, offsets of 1/4 there). Use it for a table file that the
    renderer treats as uniform.
    """
    grid = jnp.asarray(grid)
    return jnp.ones((N_DENSITIES, grid.shape[0]), dtype=grid.dtype) / (grid[-1] - grid[0])
