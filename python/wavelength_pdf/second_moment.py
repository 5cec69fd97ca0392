"""The diagonal part of the estimator's second moment, in closed form (design §4).

The second moment of C(u), which the health check and the solvers' variance penalty use,
is split into sum_j E[(f / M)(lambda_j)^2] = integral of f^2 / M (M = sum_k p_k), integrated
here in closed form in wavelength space where fireflies (small M) live, plus the cross
terms, which the u-quadrature (``quadrature``) handles well.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

Array = jax.Array


def _powers(x: Array, n: int) -> Array:
    """x^0 .. x^(n-1) by repeated products, stacked on a new last axis. Cheaper than
    pow (exp and log per element; this function ran three times slower with it) and with
    exact derivatives at x = 0 (a power with exponent 0 at base 0 has a NaN derivative)."""
    out = [jnp.ones_like(x)]
    for _ in range(n - 1):
        out.append(out[-1] * x)
    return jnp.stack(out, axis=-1)


_K5 = np.arange(5)
_BINOM5 = np.array([[1, 0, 0, 0, 0], [1, 1, 0, 0, 0], [1, 2, 1, 0, 0], [1, 3, 3, 1, 0], [1, 4, 6, 4, 1]],
                   dtype=np.float64) * (_K5[None, :] <= _K5[:, None])  # C(k, i), i <= k
_EXPO5 = np.clip(_K5[:, None] - _K5[None, :], 0, None)  # k - i
_INV_I5 = np.where(_K5 > 0, 1.0 / np.maximum(_K5, 1), 0.0)  # 1 / i, 0 for i = 0
_SERIES_TERMS = 24
_SERIES = 1.0 / (_K5[None, :] + np.arange(_SERIES_TERMS)[:, None] + 1.0)  # 1 / (k + n + 1)


def quartic_over_linear(e: Array, a: Array, b: Array, h: Array) -> Array:
    """Integral over t in [0, h] of (e0 + e1 t + ... + e4 t^4) / (a + b t), a, b >= 0.

    Closed form (log plus polynomial) when b h / a is not small, a power series in
    b t / a when it is (where the closed form cancels), and h^k / (k b) for a = 0 (infinite
    if the numerator does not vanish at t = 0). Elementwise over leading axes; e has a
    trailing axis of 5. Integer powers are products (``_powers``).
    """
    a_pos = a > 0
    a_s = jnp.where(a_pos, a, 1.0)
    b_pos = b > 0
    b_s = jnp.where(b_pos, b, 1.0)
    r = b * h / a_s
    small = a_pos & (r <= 0.2)
    hp = _powers(h, 6)  # h^0 .. h^5
    # Series: I_k = h^(k+1) / a * sum_n (-r)^n / (k + n + 1).
    r_s = jnp.where(small, r, 0.0)
    I_series = hp[..., 1:] / a_s[..., None] * (_powers(-r_s, _SERIES_TERMS) @ _SERIES)
    # Closed form: z = a + b t, I_k = b^-(k+1) [(-a)^k log(z1/z0) + sum_i C(k,i) (-a)^(k-i) (z1^i - z0^i) / i].
    z0 = a_s
    z1 = a_s + b * h
    big = a_pos & ~small
    log_ratio = jnp.log(jnp.where(big, z1 / z0, 2.0))
    pa = _powers(-a_s, 5)  # (-a)^0 .. (-a)^4
    diff_pow = (_powers(z1, 5) - _powers(z0, 5)) * _INV_I5  # (z1^i - z0^i) / i
    poly = jnp.sum(_BINOM5 * pa[..., _EXPO5] * diff_pow[..., None, :], axis=-1)
    inv_b = 1.0 / b_s
    I_closed = (pa * log_ratio[..., None] + poly) * _powers(inv_b, 6)[..., 1:]
    # a = 0: the k = 0 term diverges unless e0 = 0.
    I_zero = hp[..., :5] * _INV_I5 * inv_b[..., None]
    val_zero = jnp.where(e[..., 0] == 0, jnp.sum(e * I_zero, axis=-1), jnp.inf)
    val_zero = jnp.where(b_pos, val_zero, jnp.where(jnp.all(e == 0, axis=-1), 0.0, jnp.inf))
    I = jnp.where(small[..., None], I_series, I_closed)
    return jnp.where(a_pos, jnp.sum(e * I, axis=-1), val_zero)


def diag_second_moment(arr: dict, msum_nodes: Array) -> Array:
    """Integral of f^2 / M, per channel ((K, 3) with surface colours); see ``_diag_one``."""
    if arr["spec"].ndim == 2:
        return jax.vmap(lambda s: _diag_one({**arr, "spec": s}, msum_nodes))(arr["spec"])
    return _diag_one(arr, msum_nodes)


def _diag_one(arr: dict, msum_nodes: Array) -> Array:
    """Integral of f^2 / M over the grid range, per channel, exactly.

    M = sum_k p_k is the mixture (times 4) given at the table nodes. This is the part
    sum_j E[(f(lambda_j) / M(lambda_j))^2] of E[C^2], where fireflies live: done in
    wavelength space (u = F_j(lambda)), where on every node interval f^2 is a quartic and
    M is linear, so it has no quadrature error however small M gets.
    """
    A, B, Cq = _interval_coefficients(arr, arr["spec"])
    d = jnp.stack([A * A, 2 * A * B, B * B + 2 * A * Cq, 2 * B * Cq, Cq * Cq], axis=-1)  # (n, 3, 5)
    return _over_mixture(arr, d, msum_nodes)


def weighted_second_moment(arr: dict, msum_nodes: Array, W: Array) -> Array:
    """Integral of f' W f / M over the grid range, exactly, for the surface colours' f (the
    vector of every colour's three channels, colour-major: K * 3) and a symmetric weight W
    (K * 3, K * 3): the same-wavelength part of a weighted second moment across colours and
    channels, which the ``pixels`` objective's dispersive paths need (design §4.6). On every
    node interval f' W f is a quartic, as f^2 is in ``_diag_one``."""
    K = arr["spec"].shape[0]
    A, B, Cq = (x.reshape(x.shape[0], K * 3) for x in
                (jnp.moveaxis(y, 0, 1) for y in jax.vmap(lambda s: _interval_coefficients(arr, s))(arr["spec"])))

    def form(x, y):
        return jnp.einsum("na,ab,nb->n", x, W, y)

    d = jnp.stack([form(A, A), 2 * form(A, B), form(B, B) + 2 * form(A, Cq), 2 * form(B, Cq), form(Cq, Cq)],
                  axis=-1)  # (n, 5)
    return _over_mixture(arr, d[:, None, :], msum_nodes)[0]


def _interval_coefficients(arr: dict, spec: Array) -> tuple[Array, Array, Array]:
    """f = spec * cmf on every node interval as A + B t + C t^2 (t from the interval's start),
    each (n, 3)."""
    x = arr["nodes"]
    h = x[1:] - x[:-1]
    s0, s1 = spec[:-1], (spec[1:] - spec[:-1]) / h
    k0 = arr["cmf"][:-1]
    k1 = (arr["cmf"][1:] - arr["cmf"][:-1]) / h[:, None]
    return s0[:, None] * k0, s0[:, None] * k1 + s1[:, None] * k0, s1[:, None] * k1


def _over_mixture(arr: dict, d: Array, msum_nodes: Array) -> Array:
    """Sum over the node intervals of the integral of the quartics d (n, c, 5: coefficients
    of t^0 .. t^4 on each interval) over the mixture M, linear on each interval: (c,)."""
    grid = arr["grid"]
    x = arr["nodes"]
    h = x[1:] - x[:-1]
    m = jnp.interp(x, grid, msum_nodes, left=0.0, right=0.0)
    m0, m1 = m[:-1], m[1:]
    # Orient every interval so that M is smallest at t = 0: t -> h - t flips the quartic.
    flip = m1 < m0
    binom = jnp.array([[1, 0, 0, 0, 0], [1, 1, 0, 0, 0], [1, 2, 1, 0, 0], [1, 3, 3, 1, 0], [1, 4, 6, 4, 1]], dtype=h.dtype)
    kk = jnp.arange(5.0)
    # e_i = (-1)^i sum_{k >= i} C(k, i) d_k h^(k - i)
    hp = h[:, None, None] ** jnp.clip(kk[:, None] - kk[None, :], 0.0, None)  # (n, k, i)
    flipped = jnp.einsum("nck,ki,nki->nci", d, binom, hp) * (-1.0) ** kk
    e = jnp.where(flip[:, None, None], flipped, d)
    a = jnp.minimum(m0, m1)
    b = jnp.abs(m1 - m0) / h
    a3 = jnp.broadcast_to(a[:, None], e.shape[:2])
    b3 = jnp.broadcast_to(b[:, None], e.shape[:2])
    h3 = jnp.broadcast_to(h[:, None], e.shape[:2])
    vals = quartic_over_linear(e, a3, b3, h3)
    # Intervals past the last real node (padding) are not part of the range.
    inside = (x[1:] <= grid[-1])[:, None]
    return jnp.sum(jnp.where(inside, vals, 0.0), axis=0)
