"""Colorimetry of the objective: CIE 1931 2-degree CMFs, XYZ -> CIELAB, CIEDE2000 (design §4).

The colour matching functions and the D65 white point come from colour-science. The
conversion to CIELAB and the CIEDE2000 difference are re-written here in jax.numpy because
the objective must be differentiated through them (colour-science is NumPy only). They
follow colour-science's formulas term by term (checked to 1e-10 in the tests) with one
difference: every square root, arctangent and cube root is guarded so that its derivative
stays finite where the function itself is not differentiable (C = 0, hue of a grey,
Delta E = 0). There the derivative returned is 0, a valid subgradient.

References
----------
CIE 015:2018 Colorimetry, 4th edition (CIELAB).
Sharma, G., Wu, W., Dalal, E. N. (2005). The CIEDE2000 color-difference formula:
implementation notes, supplementary test data, and mathematical observations.
Color Research & Application 30(1), 21-30.
"""

from __future__ import annotations

from functools import lru_cache

import jax
import jax.numpy as jnp
import numpy as np

Array = jax.Array

#: colour-science's name of the CIE 1931 2-degree standard observer.
OBSERVER = "CIE 1931 2 Degree Standard Observer"


@lru_cache(maxsize=1)
def cmfs() -> tuple[np.ndarray, np.ndarray]:
    """CIE 1931 2-degree colour matching functions as tabulated by the CIE.

    Returns
    -------
    wavelengths : (K,) float64 array, nm
        360..830 nm in 1 nm steps (colour-science's ``MSDS_CMFS``).
    values : (K, 3) float64 array
        xbar, ybar, zbar. The objective treats them as piecewise linear between these
        nodes and zero outside.
    """
    from . import colour_data  # colour-science's table, without importing it each run

    wl, vals = colour_data.cmfs()
    wl.setflags(write=False)
    vals.setflags(write=False)
    return wl, vals


@lru_cache(maxsize=1)
def white_d65() -> np.ndarray:
    """XYZ of the D65 white point with Y = 1 (CIE 1931 2-degree chromaticity 0.3127, 0.3290)."""
    from . import colour_data

    xyz = colour_data.white_d65()
    xyz.setflags(write=False)
    return xyz


def _safe_sqrt(x: Array) -> Array:
    """sqrt(x) for x >= 0 whose derivative at x <= 0 is 0 instead of inf/NaN."""
    pos = x > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, x, 1.0)), 0.0)


def _safe_hypot(a: Array, b: Array) -> Array:
    return _safe_sqrt(a * a + b * b)


def _safe_hue_deg(b: Array, a: Array) -> Array:
    """atan2(b, a) in degrees in [0, 360); 0 for a = b = 0 (as colour-science does)."""
    zero = (a == 0) & (b == 0)
    h = jnp.degrees(jnp.arctan2(jnp.where(zero, 1.0, b), jnp.where(zero, 1.0, a)))
    return jnp.where(zero, 0.0, jnp.mod(h, 360.0))


def _lab_f(t: Array) -> Array:
    """CIE 1976 intermediate lightness function f(t) (CIE 015:2018, eq. 8.x).

    f(t) = t^(1/3) above (24/116)^3, else (841/108) t + 16/116.
    """
    big = t > (24.0 / 116.0) ** 3
    return jnp.where(big, jnp.cbrt(jnp.where(big, t, 1.0)), (841.0 / 108.0) * t + 16.0 / 116.0)


def xyz_to_lab(xyz: Array, white: Array | None = None) -> Array:
    """CIE XYZ (white Y = 1 scale) to CIELAB (L* in 0..100).

    Parameters
    ----------
    xyz : (..., 3) array
    white : (3,) array, optional
        Reference white XYZ; D65 with Y = 1 by default (design §4).

    Returns
    -------
    (..., 3) array
        L*, a*, b*.
    """
    if white is None:
        white = white_d65()
    xyz = jnp.asarray(xyz)
    white = jnp.asarray(white, dtype=xyz.dtype)
    fx = _lab_f(xyz[..., 0] / white[0])
    fy = _lab_f(xyz[..., 1] / white[1])
    fz = _lab_f(xyz[..., 2] / white[2])
    return jnp.stack([116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)], axis=-1)


def delta_e_2000(lab1: Array, lab2: Array) -> Array:
    """CIEDE2000 colour difference (k_L = k_C = k_H = 1), differentiable.

    Same formulas and branch conventions as ``colour.delta_E(..., method='CIE 2000')``
    (Sharma et al. 2005); the guarded square roots and arctangents give finite
    derivatives everywhere.

    Parameters
    ----------
    lab1, lab2 : (..., 3) arrays, broadcastable
        CIELAB with L* in 0..100.

    Returns
    -------
    (...) array
        Delta E_00.
    """
    lab1 = jnp.asarray(lab1)
    lab2 = jnp.asarray(lab2)
    L1, a1, b1 = lab1[..., 0], lab1[..., 1], lab1[..., 2]
    L2, a2, b2 = lab2[..., 0], lab2[..., 1], lab2[..., 2]

    # Chroma and the a* rescaling G that makes near-neutral hues behave.
    c1 = _safe_hypot(a1, b1)
    c2 = _safe_hypot(a2, b2)
    c_bar = 0.5 * (c1 + c2)
    c_bar7 = c_bar**7
    g = 0.5 * (1.0 - _safe_sqrt(c_bar7 / (c_bar7 + 25.0**7)))
    ap1 = (1.0 + g) * a1
    ap2 = (1.0 + g) * a2
    cp1 = _safe_hypot(ap1, b1)
    cp2 = _safe_hypot(ap2, b2)
    hp1 = _safe_hue_deg(b1, ap1)
    hp2 = _safe_hue_deg(b2, ap2)

    # Differences in lightness, chroma and hue.
    dL = L2 - L1
    dC = cp2 - cp1
    dh_raw = hp2 - hp1
    cprod = cp1 * cp2
    dh = jnp.where(
        cprod == 0,
        0.0,
        jnp.where(
            jnp.abs(dh_raw) <= 180.0,
            dh_raw,
            jnp.where(dh_raw > 180.0, dh_raw - 360.0, dh_raw + 360.0),
        ),
    )
    dH = 2.0 * _safe_sqrt(cprod) * jnp.sin(jnp.radians(0.5 * dh))

    # Means, with the hue mean taken the short way round the circle.
    L_bar = 0.5 * (L1 + L2)
    cp_bar = 0.5 * (cp1 + cp2)
    h_abs = jnp.abs(hp1 - hp2)
    h_sum = hp1 + hp2
    h_bar = jnp.where(
        cprod == 0,
        h_sum,
        jnp.where(
            h_abs <= 180.0,
            0.5 * h_sum,
            jnp.where(h_sum < 360.0, 0.5 * (h_sum + 360.0), 0.5 * (h_sum - 360.0)),
        ),
    )

    # Weighting functions and the rotation term.
    T = (
        1.0
        - 0.17 * jnp.cos(jnp.radians(h_bar - 30.0))
        + 0.24 * jnp.cos(jnp.radians(2.0 * h_bar))
        + 0.32 * jnp.cos(jnp.radians(3.0 * h_bar + 6.0))
        - 0.20 * jnp.cos(jnp.radians(4.0 * h_bar - 63.0))
    )
    d_theta = 30.0 * jnp.exp(-(((h_bar - 275.0) / 25.0) ** 2))
    cp_bar7 = cp_bar**7
    R_C = 2.0 * _safe_sqrt(cp_bar7 / (cp_bar7 + 25.0**7))
    L50 = (L_bar - 50.0) ** 2
    S_L = 1.0 + 0.015 * L50 / jnp.sqrt(20.0 + L50)
    S_C = 1.0 + 0.045 * cp_bar
    S_H = 1.0 + 0.015 * cp_bar * T
    R_T = -jnp.sin(jnp.radians(2.0 * d_theta)) * R_C

    tl = dL / S_L
    tc = dC / S_C
    th = dH / S_H
    return _safe_sqrt(tl * tl + tc * tc + th * th + R_T * tc * th)
