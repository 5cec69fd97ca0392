"""The objective J of design §4, evaluated exactly for one lamp spectrum.

For a table P of four densities, C(u) is the estimator of the lamp's colour (``quadrature``)
and c its exact mean (``problem``), both scaled so that c has Y = 1, and

    J = integral over u in [0, 1] of CIEDE2000(Lab(C(u)), Lab(c)) du,

integrated piecewise by Gauss-Legendre between the breakpoints in u (``quadrature``). Its
first and second moments come along: E[C] from the same quadrature, E[(C - c)^2] from it and
the closed-form diagonal part (``second_moment``). The solvers minimize J plus a variance
penalty (:func:`penalized`); stratified uniform sampling's figures are in ``uniform``.

What no breakpoint can know is where CIEDE2000 itself is not smooth: it jumps where the
hue of C(u) crosses the opposite of the target's hue (the hue-mean branch; Sharma et al.
2005) and has a cone point where C(u) passes through c. On optimized tables J and J_fine
agree to ~1e-6 relative; on tables whose estimates wander round the hue circle or sweep
straight through c (a single emission line) the difference is 1e-5 to 1e-3.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from . import aot, colorimetry, sampling
from .problem import SHARE, SHARED, Problem
from .quadrature import ORDER, ORDER_FINE, SEARCH_ORDER, gauss_legendre, normalized, table_estimate, table_quadrature
from .second_moment import diag_second_moment, weighted_second_moment

Array = jax.Array


def _delta_e(arr: dict, C: Array) -> Array:
    """CIEDE2000 of C(u) ((n, 3), or (K, n, 3) with surface colours) against the target."""
    lab_c = arr["lab_c"][:, None, :] if C.ndim == 3 else arr["lab_c"]
    return colorimetry.delta_e_2000(colorimetry.xyz_to_lab(C), lab_c)


def _mean_over_colours(arr: dict, per_colour: Array) -> Array:
    """J from the per-colour J's: itself, or their weighted mean (design §4.5)."""
    return jnp.sum(arr["weights"] * per_colour) if "weights" in arr else per_colour


def _strata_moments(arr: dict, u: Array, wt: Array, C: Array, D: Array, diag_exact: Array):
    """The strata count N, E[C C'] (d, d) with its diagonal's exact part, and m (N, d), the
    integrals of C over the N equal strata of u, for path colours C (points, d)."""
    n = arr["strata"].shape[0] + 1
    idx = jnp.clip(jnp.floor(u * n).astype(jnp.int32), 0, n - 1)
    second = C.T @ (wt[:, None] * C) + jnp.diag(diag_exact - jnp.sum(wt[:, None] * D, axis=0))
    return n, second, jax.ops.segment_sum(wt[:, None] * C, idx, num_segments=n)


def stratified_value(arr: dict, u: Array, wt: Array, C: Array, D: Array, diag_exact: Array) -> Array:
    """The ``stratified`` objective (design §4.6): sqrt(N tr(M Cov)), Cov the covariance of
    the mean of N samples of C(u), one u in each stratum [i/N, (i+1)/N), and M CIEDE2000's
    quadratic form in XYZ at the target (``problem.with_objective``); the weighted mean over
    surface colours of the same.

    Cov = E[C C'] / N - sum_i m_i m_i', m_i the integral of C over stratum i (the
    within-stratum covariances summed over N^2). E[C C']'s diagonal takes the exact part of
    the second moment (wavelength space), as J's moments do: the quadrature only sees
    C^2 - sum_j (f_j / M_j)^2 there.
    """
    def one(C, D, diag_exact, M):
        n, second, m = _strata_moments(arr, u, wt, C, D, diag_exact)
        cov = second / n - m.T @ m
        return jnp.sqrt(jnp.maximum(n * jnp.sum(M * cov), 0.0))

    if C.ndim == 2:
        return one(C, D, diag_exact, arr["strata_metric"])
    diag = jnp.broadcast_to(diag_exact, C.shape[:1] + (3,))
    return _mean_over_colours(arr, jax.vmap(one)(C, D, diag, arr["strata_metric"]))


def pixel_value(arr: dict, u: Array, wt: Array, C: Array, D: Array, diag_exact: Array, dispersed: Array) -> Array:
    """The ``pixels`` objective (design §4.6): sqrt(N V), V the predicted mean squared
    CIEDE2000 over a scene's pixels of their means of N samples, the surface colours being a
    hat basis of the pixels' spectra (:func:`wavelength_pdf.predict.pixel_de2`, made linear in
    the basis' covariances by :func:`wavelength_pdf.predict.pixel_weights`):

        V = tr(W_s M_s) + tr(W_i M_i) + tr(W_1 O),

    M_s = S / N - sum_i m_i m_i' (stratified), M_i = (S - m m') / N (independent), with
    S = E[C C'] across every colour and channel and m_i its strata's integrals of C, as
    :func:`stratified_value` for one colour (S's diagonal takes the exact part);
    O = 4 ∫ f f' / M dλ - c c', one path that kept one wavelength, whose weighted
    integral ``dispersed`` = ∫ f' W_1 f / M is exact (``second_moment``). With the spread's
    parts that ``pbrt --wavelength-net`` stratifies (``pixel_wk``), each adds
    tr(W_k (S - n_k sum_j m_kj m_kj')) / N, C(u)'s covariance within n_k = 2^k strata, whose
    integrals m_kj are sums of the N strata's.
    """
    K = C.shape[0]
    Cf = jnp.moveaxis(C, 0, 1).reshape(-1, 3 * K)  # (points, K * 3), colour-major
    Df = jnp.moveaxis(D, 0, 1).reshape(-1, 3 * K)
    n, S, m = _strata_moments(arr, u, wt, Cf, Df, diag_exact.reshape(-1))  # m: (n, K * 3)
    mean = jnp.sum(m, axis=0)
    c = arr["c"].reshape(-1)
    V = (jnp.sum(arr["pixel_ws"] * (S / n - m.T @ m)) + jnp.sum(arr["pixel_wi"] * (S - jnp.outer(mean, mean))) / n
         + 4.0 * dispersed - c @ arr["pixel_w1"] @ c)
    for k in range(arr["pixel_wk"].shape[0] if "pixel_wk" in arr else 0):  # static: unrolled
        nk = 2 ** (k + 1)
        mk = m.reshape(nk, n // nk, -1).sum(axis=1)
        V = V + jnp.sum(arr["pixel_wk"][k] * (S - nk * mk.T @ mk)) / n
    return jnp.sqrt(jnp.maximum(n * V, 0.0))


def estimator_moments(arr: dict, wt: Array, C: Array, D: Array, diag_exact: Array, u: Array,
                      dispersed: Array | float = 0.0):
    """J, E[C] and E[(C - c)^2] (per channel); J is the ``stratified`` value instead where
    the problem stands for it (design §4.6).

    E[C^2] = (exact diagonal part, wavelength space) + (cross terms, u-quadrature): the
    quadrature only sees C^2 - sum_j (f_j / M_j)^2, which has no firefly peaks.
    """
    stratified = "strata" in arr  # the value is then not J's, and J's CIEDE2000 is not taken
    if C.ndim == 2:  # one white surface: the sums the solvers were tuned on (their rounding
        # moves the optimum found on hard lamps), kept apart from the surface colours' axes
        J = None if stratified else jnp.sum(wt * _delta_e(arr, C))
        m1 = jnp.sum(wt[:, None] * C, axis=0)
        cross = jnp.sum(wt[:, None] * (C * C - D), axis=0)
    else:
        J = None if stratified else _mean_over_colours(arr, jnp.sum(wt * _delta_e(arr, C), axis=-1))
        m1 = jnp.sum(wt[:, None] * C, axis=-2)
        cross = jnp.sum(wt[:, None] * (C * C - D), axis=-2)
    c = arr["c"]
    m2 = diag_exact + cross - 2.0 * c * m1 + c * c
    if "pixel_ws" in arr:
        J = pixel_value(arr, u, wt, C, D, diag_exact, dispersed)
    elif stratified:
        J = stratified_value(arr, u, wt, C, D, diag_exact)
    return J, m1, m2


def as_sampled(P: Array, arr: dict) -> Array:
    """The table P as it is sampled: each density normalized, and with a problem's fixed share
    (:func:`wavelength_pdf.problem.with_share`) mixed in."""
    PN = jax.vmap(lambda p: sampling.normalize(arr["grid"], p))(P)
    if SHARE not in arr:
        return PN
    return (1.0 - arr[SHARE]) * PN + arr[SHARE] * arr[SHARED]


def _table_moments(P: Array, arr: dict, glx: Array, glw: Array):
    P = PN = as_sampled(P, arr)
    u, wt, C, D = table_quadrature(P, arr, glx, glw)
    msum = jnp.sum(PN, axis=0)
    dispersed = weighted_second_moment(arr, msum, arr["pixel_w1"]) if "pixel_w1" in arr else 0.0
    return estimator_moments(arr, wt, C, D, diag_second_moment(arr, msum), u, dispersed)


def penalized(P: Array, arr: dict, glx: Array, glw: Array, var_ref: Array, mu: Array, margin: Array):
    """J + mu * sum_c max(0, var_c / var_ref_c - (1 - margin))^2, and (J, E[C], E[(C-c)^2]).

    The objective of the solvers (see ``solvers``); with mu = 0 it is J itself. Every
    evaluation at ``ORDER`` goes through this one function, so it is compiled once (per
    size class) for searching, reporting and the health figures alike.
    """
    J, m1, m2 = _table_moments(P, arr, glx, glw)
    var = m2 - (m1 - arr["c"]) ** 2
    excess = jnp.maximum(var / var_ref - (1.0 - margin), 0.0)
    return J + mu * jnp.sum(excess * excess), (J, m1, m2)


# Jitted at the edge (where solvers and reports call in); shapes are fixed per size class.
# Their executables are also kept on disk (``aot``) when the compilation cache is on.
penalized_value_and_grad = aot.DiskJit(jax.jit(jax.value_and_grad(penalized, has_aux=True)),
                                       "penalized_value_and_grad")
_table_moments_jit = aot.DiskJit(jax.jit(_table_moments), "table_moments")


def _moments_at(problem: Problem, P: Array, order: int):
    glx, glw = gauss_legendre(order)
    if order == SEARCH_ORDER:
        one = np.ones(3)
        (_, aux), _ = penalized_value_and_grad(P, problem.arrays, glx, glw, one, 0.0, 0.0)
        return aux
    if order < ORDER_FINE:
        # The same compiled function as ORDER_FINE (one compilation fewer per process):
        # the rule's points repeated with zero weight.
        reps = -(-ORDER_FINE // order)
        glx = jax.device_put(np.tile(np.asarray(glx), reps)[:ORDER_FINE])
        glw = jax.device_put(np.concatenate([np.asarray(glw), np.zeros(ORDER_FINE - order)]))
    return _table_moments_jit(P, problem.arrays, glx, glw)


def _check_table(problem: Problem, P) -> Array:
    P = jnp.asarray(P, dtype=jnp.float64)
    if P.shape != (sampling.N_DENSITIES, problem.grid.size):
        raise ValueError(
            f"densities must have shape ({sampling.N_DENSITIES}, {problem.grid.size}), got {P.shape}"
        )
    return P


def target(problem: Problem) -> np.ndarray:
    """The exact target XYZ c (Y = 1)."""
    return problem.c.copy()


def estimate(problem: Problem, P, u) -> np.ndarray:
    """The estimator C(u) of the table P (4, M+1) at the u values given, shape (n, 3)."""
    P = _check_table(problem, P)
    arr = problem.arrays
    PN, FF = normalized(arr["grid"], as_sampled(P, arr))
    return np.asarray(table_estimate(arr, PN, FF, jnp.atleast_1d(jnp.asarray(u))))


def J(problem: Problem, P, order: int = ORDER) -> float:
    """J of the table P (any positive scale per density) with ``order`` GL points a piece."""
    return float(_moments_at(problem, _check_table(problem, P), order)[0])


def J_pair(problem: Problem, P) -> tuple[float, float]:
    """J at the optimizer's resolution and at the refined one: (J, J_fine)."""
    return J(problem, P, ORDER), J(problem, P, ORDER_FINE)


def value_and_grad(problem: Problem):
    """A function P -> (J, dJ/dP) at ``ORDER`` (jitted, float64)."""
    glx, glw = gauss_legendre(ORDER)
    arr = problem.arrays
    one = jnp.ones(3)

    def vg(P):
        (val, _), g = penalized_value_and_grad(jnp.asarray(P, dtype=jnp.float64), arr, glx, glw, one, 0.0, 0.0)
        return val, g

    return vg


def moments(problem: Problem, P, order: int = ORDER_FINE) -> tuple[float, np.ndarray, np.ndarray]:
    """J, E[C] and E[(C - c)^2] over u (per channel) of the table P."""
    J_, m1, m2 = _moments_at(problem, _check_table(problem, P), order)
    return float(J_), np.asarray(m1), np.asarray(m2)
