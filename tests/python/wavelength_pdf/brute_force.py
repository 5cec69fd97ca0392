"""One path's colour C(u) computed the slow, obvious way, for tests of the objective: NumPy
interpolation of the spectrum and the CMFs, the exact target by a fine midpoint rule, and
the wavelengths from the sampler alone (not the objective's quadrature)."""
from __future__ import annotations

import jax
import numpy as np

from wavelength_pdf import colorimetry, sampling

_cmf_wl, _cmf = colorimetry.cmfs()


def lamp_colour(spectrum, lo: float, hi: float):
    """(f, c): f(lambda) = I * (xbar, ybar, zbar) at any wavelengths, and its exact integral
    c over [lo, hi] by a midpoint rule fine enough for float64-level agreement."""

    def f(lam):
        spec = np.interp(lam, spectrum.wavelengths, spectrum.values, left=0.0, right=0.0)
        cmf = np.stack([np.interp(lam, _cmf_wl, _cmf[:, i], left=0.0, right=0.0) for i in range(3)], axis=-1)
        return spec[..., None] * cmf

    fine = np.unique(np.concatenate([np.linspace(lo, hi, 200_001), spectrum.wavelengths, _cmf_wl]))
    fine = fine[(fine >= lo) & (fine <= hi)]
    return f, np.sum(f(0.5 * (fine[1:] + fine[:-1])) * np.diff(fine)[:, None], axis=0)


def table_colours(f, grid: np.ndarray, P: np.ndarray, u: np.ndarray) -> np.ndarray:
    """C(u) (len(u), 3) of table P on ``grid``: sum over the four wavelengths of f / mixture."""
    lam = np.asarray(jax.jit(sampling.sample_four)(grid, P, u))
    m = 4.0 * np.asarray(jax.jit(sampling.mixture_pdf)(grid, P, lam))
    return np.sum(f(lam) / m[..., None], axis=0)


def assert_gradient_matches_finite_differences(value_and_grad, P: np.ndarray, directions: int = 3) -> np.ndarray:
    """Central differences (step 1e-6 along random directions scaled by P) agree with the
    gradient to 1e-5 relative; returns the gradient."""
    value, g = value_and_grad(P)
    g = np.asarray(g)
    assert np.isfinite(float(value)) and np.all(np.isfinite(g))
    rng = np.random.default_rng(0)
    for _ in range(directions):
        d = rng.normal(size=P.shape) * P
        h = 1e-6
        fd = (float(value_and_grad(P + h * d)[0]) - float(value_and_grad(P - h * d)[0])) / (2 * h)
        assert abs(fd - np.sum(g * d)) <= 1e-5 * max(abs(fd), 1e-3), (fd, np.sum(g * d))
    return g
