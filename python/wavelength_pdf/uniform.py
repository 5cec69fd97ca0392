"""The baseline every table is judged against: stratified uniform sampling (design §4).

Its four wavelengths are lambda_j = lo + (hi - lo) ((u + j/4) mod 1): the balance heuristic
over four uniform densities. Its J, moments and estimator come from the same quadrature and
closed-form second moment as a table's (``objective``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from . import aot, sampling
from .objective import estimator_moments
from .problem import Problem
from .quadrature import ORDER, f_at, gauss_legendre, pieces
from .second_moment import diag_second_moment

Array = jax.Array


def _uniform_breaks(arr: dict, lo: Array, hi: Array) -> Array:
    x = (arr["bp"] - lo) / (hi - lo)
    j = jnp.arange(sampling.N_DENSITIES)[:, None] / sampling.N_DENSITIES
    breaks = jnp.mod(x[None, :] - j, 1.0).ravel()
    # The strata's edges of the ``stratified`` objective (design §4.6), as for a table.
    return jnp.concatenate([breaks, arr["strata"]]) if "strata" in arr else breaks


def _uniform_terms(arr: dict, u: Array) -> Array:
    """Stratified uniform terms f(lambda_j) / sum_k p_k(lambda_j), shape (4, n, 3): the
    balance heuristic over four uniform densities at the stratified wavelengths."""
    grid = arr["grid"]
    lo, hi = grid[0], grid[-1]
    lam = sampling.sample_stratified_uniform(lo, hi, u)  # (4, n)
    msum = sampling.N_DENSITIES * sampling.mixture_pdf(grid, sampling.stratified_uniform_table(grid), lam)
    return f_at(arr, lam) / msum[..., None]


def _uniform_estimate(arr: dict, u: Array) -> Array:
    """Stratified uniform C(u) = (hi - lo) / 4 * sum_j f(lambda_j)."""
    return jnp.sum(_uniform_terms(arr, u), axis=-3)


def _uniform_moments(arr: dict, glx: Array, glw: Array):
    grid = arr["grid"]
    u, wt = pieces(_uniform_breaks(arr, grid[0], grid[-1]), glx, glw)
    terms = _uniform_terms(arr, u)
    msum = jnp.sum(sampling.stratified_uniform_table(grid), axis=0)
    return estimator_moments(arr, wt, jnp.sum(terms, axis=-3), jnp.sum(terms * terms, axis=-3),
                             diag_second_moment(arr, msum), u)


_uniform_moments_jit = aot.DiskJit(jax.jit(_uniform_moments), "uniform_moments")


def uniform_estimate(problem: Problem, u) -> np.ndarray:
    """The stratified-uniform estimator C(u), shape (n, 3)."""
    return np.asarray(_uniform_estimate(problem.arrays, jnp.atleast_1d(jnp.asarray(u))))


def uniform_moments(problem: Problem, order: int = ORDER) -> tuple[float, np.ndarray, np.ndarray]:
    """J, E[C] and E[(C - c)^2] of stratified uniform sampling over the grid range."""
    glx, glw = gauss_legendre(order)
    J_, m1, m2 = _uniform_moments_jit(problem.arrays, glx, glw)
    return float(J_), np.asarray(m1), np.asarray(m2)


def uniform_J(problem: Problem, order: int = ORDER) -> float:
    """J of stratified uniform sampling, lambda_j = lo + (hi - lo) ((u + j/4) mod 1)."""
    return uniform_moments(problem, order)[0]
