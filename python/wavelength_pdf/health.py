"""Health of a table's estimator: what J cannot see ("degenerate optima", design §4).

J is blind to bias (it drops when a density gives up support where the spectrum is
non-zero: the colour is then estimated from the rest, consistently but wrongly) and to
rare huge errors (fireflies: J integrates a CIEDE2000 that saturates, so a tiny u-interval
with an enormous C(u) costs almost nothing). Two figures catch both:

- ``bias``: the exact relative bias of the mean of C(u), per channel. Computed in
  wavelength space, where E[C] = sum_j integral f p_j / (sum_k p_k) dlambda: on every
  interval between consecutive spectrum, CMF and table nodes the integrand is a quadratic
  times a ratio of two linear functions, integrated with high-order Gauss-Legendre (exact
  to rounding). Where the mixture is zero the integrand is zero, so a table that drops
  support where f > 0 shows exactly the mass it lost.
- ``std``: std(C(u)) / c per channel, from the u-quadrature of the objective.

The acceptance rule is one function, :func:`rejection`, used by the solvers, the optimizer's
result, ``show``, ``batch`` and the evaluation: a table is accepted when its bias is at most
``MAX_BIAS``, no channel's std is worse than the initialization's (within ``STD_RTOL``) and,
when both are known, its J is no worse than stratified uniform sampling's.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from . import aot, objective, quadrature, uniform
from .problem import Problem

#: Largest accepted relative bias of the estimator's mean (design §4).
MAX_BIAS = 1e-6

#: Relative tolerance when comparing a channel's std with the initialization's.
STD_RTOL = 1e-6

#: Gauss-Legendre points per node interval for the bias integral.
_BIAS_ORDER = 8


@dataclass(frozen=True)
class Health:
    """Estimator health of one table for one spectrum.

    Attributes
    ----------
    bias : float
        max over channels (and surface colours) of |E[C] - c| / c.
    bias_xyz : (3,) array, or (K, 3) with K surface colours (design §4.5)
        Signed relative bias per channel (E[C] - c) / c.
    std : (3,) array, or (K, 3)
        std(C(u)) / c per channel: the acceptance rule holds every colour's channels to
        the initialization's.
    missing_mass : (3,) array, or (K, 3)
        Fraction of each channel of c lying where the mixture density is zero.
    """

    bias: float
    bias_xyz: np.ndarray
    std: np.ndarray
    missing_mass: np.ndarray

    @property
    def bias_rel(self) -> float:
        """Alias of ``bias`` (the name used in reports)."""
        return self.bias

    @property
    def std_rel(self) -> np.ndarray:
        """Alias of ``std`` (the name used in reports)."""
        return self.std

    def accepted(self, reference: "Health | None" = None) -> bool:
        """True if :func:`rejection` finds nothing against this table's health."""
        return not rejection(self, reference)

    def reason(self, reference: "Health | None" = None) -> str:
        """Why the table is not accepted ('' if it is); see :func:`rejection`."""
        return rejection(self, reference)

    def summary(self) -> str:
        s = self.std if np.ndim(self.std) == 1 else np.max(self.std, axis=0)
        return f"bias={self.bias:.2e} std/c=({s[0]:.4g},{s[1]:.4g},{s[2]:.4g})"


def _number(x: float) -> str:
    """x for a message: never 'nan' (design §3.3)."""
    return "not a number" if np.isnan(x) else f"{x:.3g}"


def rejection(health: "Health", reference: "Health | None" = None, J: float | None = None,
              J_uniform: float | None = None) -> str:
    """Why a table is not accepted, or '' if it is: the project's one acceptance rule.

    Parameters
    ----------
    health : Health
        The table's estimator health.
    reference : Health, optional
        The initialization's health: no channel's std may exceed it (within STD_RTOL).
    J, J_uniform : float, optional
        The table's J and stratified uniform sampling's: a table worse than uniform
        (``J > J_uniform``) is never accepted.
    """
    if not (np.isfinite(health.bias) and health.bias <= MAX_BIAS):
        return f"relative bias {_number(health.bias)} exceeds {MAX_BIAS:g}"
    if not np.all(np.isfinite(health.std)):
        return "std of the estimator is not finite"
    if reference is not None:
        worse = health.std > reference.std * (1.0 + STD_RTOL)
        if np.any(worse):
            # With surface colours (design §4.5) std is (K, 3): name the first colour too.
            where = ""
            if worse.ndim == 2:
                k = int(np.flatnonzero(worse.any(axis=1))[0])
                where, worse = f" of surface colour #{k}", worse[k]
            ch = ",".join("XYZ"[i] for i in np.flatnonzero(worse))
            return f"std/c worse than the initialization's in channel(s) {ch}{where}"
    if J is not None and J_uniform is not None:
        if not np.isfinite(J):
            return f"J is {_number(J)}"
        if J > J_uniform:
            return f"J {J:.6g} is worse than stratified uniform sampling's {J_uniform:.6g}"
    return ""


def _mean_in_wavelength(arr: dict, P: jax.Array, glx: jax.Array, glw: jax.Array):
    """E[C] = sum_j integral f p_j / sum_k p_k, and integral of f where the mixture is 0."""
    grid = arr["grid"]
    x = arr["nodes"]
    hi = grid[-1]
    a, b = x[:-1], x[1:]
    # Padding nodes lie beyond hi: their intervals get zero width.
    b = jnp.minimum(b, hi)
    a = jnp.minimum(a, hi)
    h = b - a
    lam = a[:, None] + h[:, None] * glx[None, :]
    wt = h[:, None] * glw[None, :]
    f = quadrature.f_at(arr, lam)  # (n, g, 3)
    PN = objective.as_sampled(P, arr)
    pk = jax.vmap(lambda pn: jnp.interp(lam, grid, pn))(PN)  # (4, n, g)
    m = jnp.sum(pk, axis=0)
    pos = m > 0
    share = jnp.where(pos[None], pk / jnp.where(pos, m, 1.0)[None], 0.0)
    # f is (n, g, 3), or (K, n, g, 3) with surface colours (design §4.5).
    mean = jnp.sum(jnp.sum(share, axis=0)[..., None] * f * wt[..., None], axis=(-3, -2))
    lost = jnp.sum(jnp.where(pos, 0.0, 1.0)[..., None] * f * wt[..., None], axis=(-3, -2))
    return mean, lost


_mean_in_wavelength_jit = aot.DiskJit(jax.jit(_mean_in_wavelength), "mean_in_wavelength")


def health(problem: Problem, P) -> Health:
    """Bias and per-channel relative std of the table P (4, M+1) for ``problem``.

    For the ``pixels`` objective (design §4.6), whose surface colours are a hat basis of a
    scene's pixel spectra, the figures are the lamp's on the white surface (the basis' sum):
    the objective is itself a variance over every pixel's colour, and the rule's per-channel
    guard against rare huge errors is taken where J's tables take it, not on 60 basis
    channels of which some are nearly black."""
    if problem.objective == "pixels":
        from .problem import white_of

        problem = white_of(problem)
    P = objective._check_table(problem, P)
    glx, glw = quadrature.gauss_legendre(_BIAS_ORDER)
    mean, lost = _mean_in_wavelength_jit(problem.arrays, P, glx, glw)
    c = problem.c
    bias_xyz = _relative(np.asarray(mean) - c, c)
    _, _, m2 = objective.moments(problem, P)
    std = _relative(np.sqrt(np.maximum(m2 - (np.asarray(mean) - c) ** 2, 0.0)), c)
    return Health(
        bias=float(np.max(np.abs(bias_xyz))),
        bias_xyz=bias_xyz,
        std=std,
        missing_mass=_relative(np.asarray(lost), c),
    )


def _relative(x: np.ndarray, c: np.ndarray) -> np.ndarray:
    """x / c per channel, with 0 / 0 = 0: a channel whose exact integral c is 0 has an
    integrand that is 0 wherever the lamp emits (z-bar above ~650 nm: a red or infrared lamp
    has Z = 0), so every estimate of it is exactly 0, unbiased and without noise. Any other
    x over a zero c (which rounding alone cannot give) is infinite, never NaN."""
    x = np.asarray(x, dtype=np.float64)
    c = np.broadcast_to(np.asarray(c, dtype=np.float64), x.shape)
    out = np.where(x == 0, 0.0, np.inf)
    np.divide(x, c, out=out, where=c != 0)
    return out


def uniform_health(problem: Problem) -> Health:
    """Health of stratified uniform sampling (unbiased; std from the u-quadrature)."""
    _, m1, m2 = uniform.uniform_moments(problem)
    c = problem.c
    b = _relative(m1 - c, c)
    std = _relative(np.sqrt(np.maximum(m2 - (m1 - c) ** 2, 0.0)), c)
    return Health(bias=float(np.max(np.abs(b))), bias_xyz=b, std=std, missing_mass=np.zeros(np.shape(c)))
