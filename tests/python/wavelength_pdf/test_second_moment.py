"""The closed-form integral of a quartic over a linear function (the exact diagonal part
of the second moment, second_moment.diag_second_moment) against adaptive quadrature, on
every branch: the power series (b h / a small), the closed form, and a = 0."""

import numpy as np
import pytest
from scipy.integrate import quad

import jax
import jax.numpy as jnp

from wavelength_pdf import second_moment
from wavelength_pdf.precision import float64


def _reference(e, a, b, h):
    return quad(lambda t: np.polyval(e[::-1], t) / (a + b * t), 0.0, h,
                epsabs=0.0, epsrel=1e-13, limit=200)[0]


@float64
@pytest.mark.parametrize("r_range", [(1e-6, 0.2), (0.2, 5.0), (5.0, 1e4)], ids=["series", "mid", "large"])
def test_quartic_over_linear_matches_quadrature(r_range):
    rng = np.random.default_rng(7)
    n = 40
    a = rng.uniform(0.01, 2.0, n)
    h = rng.uniform(0.01, 5.0, n)
    r = np.exp(rng.uniform(np.log(r_range[0]), np.log(r_range[1]), n))  # r = b h / a
    b = r * a / h
    e = rng.uniform(0.0, 1.0, (n, 5))
    got = np.asarray(second_moment.quartic_over_linear(jnp.asarray(e), jnp.asarray(a), jnp.asarray(b), jnp.asarray(h)))
    ref = np.array([_reference(*args) for args in zip(e, a, b, h)])
    np.testing.assert_allclose(got, ref, rtol=1e-9)


@float64
def test_quartic_over_linear_at_a_zero():
    # a = 0: integral of t^k / (b t) = h^k / (k b) for k >= 1; infinite with e0 > 0.
    e = jnp.asarray([[0.0, 1.0, 2.0, 0.5, 0.25], [1.0, 0.0, 0.0, 0.0, 0.0], [0.0] * 5])
    a = jnp.zeros(3)
    b = jnp.asarray([2.0, 2.0, 0.0])
    h = jnp.asarray([1.5, 1.5, 1.5])
    got = np.asarray(second_moment.quartic_over_linear(e, a, b, h))
    expect = sum(float(e[0, k]) * 1.5**k / (k * 2.0) for k in range(1, 5))
    assert got[0] == pytest.approx(expect, rel=1e-14)
    assert np.isposinf(got[1])
    assert got[2] == 0.0


@float64
def test_quartic_over_linear_gradient_matches_finite_differences():
    e = jnp.asarray([[0.3, 0.2, 0.1, 0.05, 0.02]] * 3)
    h = jnp.asarray([0.7, 0.7, 0.7])
    a = jnp.asarray([0.5, 0.5, 0.5])
    b = jnp.asarray([0.01, 0.5, 50.0])  # series, closed form near the switch, large r
    g = jax.grad(lambda a, b: jnp.sum(second_moment.quartic_over_linear(e, a, b, h)), argnums=(0, 1))(a, b)
    f = lambda a, b: np.asarray(second_moment.quartic_over_linear(e, jnp.asarray(a), jnp.asarray(b), h))  # noqa: E731
    step = 1e-6
    for i, x in enumerate((np.asarray(a), np.asarray(b))):
        d = step * np.maximum(np.abs(x), 1e-3)
        args_p = [np.asarray(a), np.asarray(b)]
        args_m = [np.asarray(a), np.asarray(b)]
        args_p[i] = x + d
        args_m[i] = x - d
        fd = (f(*args_p) - f(*args_m)) / (2 * d)
        np.testing.assert_allclose(np.asarray(g[i]), fd, rtol=1e-6)
