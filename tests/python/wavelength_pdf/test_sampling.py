"""The sampling model of design §1: sample / pdf / invert triples of a piecewise-linear density."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.stats

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import sampling

GRID = np.arange(380.0, 781.0, 5.0)

# Jitted once for the module: op-by-op dispatch would make these tests slow.
_sample = jax.jit(sampling.sample)
_invert = jax.jit(sampling.invert)
_pdf = jax.jit(sampling.pdf)


def _density_with_zeros(seed: int = 0) -> np.ndarray:
    """Random density with leading/trailing zero runs, an interior gap and a lone zero."""
    rng = np.random.default_rng(seed)
    p = rng.random(GRID.size)
    p[:3] = 0.0
    p[-5:] = 0.0
    p[20:30] = 0.0
    p[45] = 0.0
    return p


def _support(p: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """True where the density is positive in an open neighbourhood of lam."""
    return np.asarray(_pdf(GRID, p, lam)) > 0


def test_normalize_integrates_to_one_by_trapezoid_and_exactly():
    p = _density_with_zeros() * 37.5
    pn = np.asarray(sampling.normalize(GRID, p))
    assert abs(np.trapezoid(pn, GRID) - 1.0) < 1e-14
    # The density is linear between nodes: a much finer trapezoid rule is exact too.
    fine = np.linspace(GRID[0], GRID[-1], 40001)
    assert abs(np.trapezoid(np.asarray(_pdf(GRID, p, fine)), fine) - 1.0) < 1e-12


def test_pdf_is_zero_outside_the_grid():
    p = np.ones(GRID.size)
    assert float(_pdf(GRID, p, 379.999)) == 0.0
    assert float(_pdf(GRID, p, 780.001)) == 0.0
    assert float(_pdf(GRID, p, 500.0)) == pytest.approx(1.0 / 400.0, rel=1e-14)


def test_cdf_matches_integral_of_pdf():
    p = _density_with_zeros(1)
    F = np.asarray(sampling.cdf(GRID, p))
    assert F[0] == 0.0 and F[-1] == 1.0
    lam = np.linspace(380.0, 780.0, 997)
    fine = np.linspace(380.0, 780.0, 400 * 64 + 1)
    cum = np.concatenate([[0.0], np.cumsum(np.diff(fine) * 0.5 * (np.asarray(_pdf(GRID, p, fine[1:]))
                                                                  + np.asarray(_pdf(GRID, p, fine[:-1]))))])
    # Every wavelength in `lam` is not a node of `fine`, so compare with interpolation of
    # the fine cumulative integral (quadratic error ~ (400/25600)^2 * max|p'|).
    want = np.interp(lam, fine, cum)
    got = np.asarray(_invert(GRID, p, lam))
    assert np.max(np.abs(got - want)) < 1e-6, np.max(np.abs(got - want))


def test_round_trip_invert_of_sample_is_identity():
    p = _density_with_zeros(2)
    u = np.linspace(0.0, 1.0, 20001)
    lam = np.asarray(_sample(GRID, p, u))
    back = np.asarray(_invert(GRID, p, lam))
    err = np.max(np.abs(back - u))
    assert err < 1e-13, f"max |F(F^-1(u)) - u| = {err}"


def test_round_trip_sample_of_invert_is_identity_on_the_support():
    p = _density_with_zeros(3)
    lam = np.linspace(380.0, 780.0, 8001)
    lam = lam[_support(p, lam)]
    u = np.asarray(_invert(GRID, p, lam))
    again = np.asarray(_sample(GRID, p, u))
    err = np.max(np.abs(again - lam))
    assert err < 1e-8, f"max |F^-1(F(lambda)) - lambda| = {err} nm"


def test_sample_is_monotone_and_never_lands_where_the_density_is_zero():
    p = _density_with_zeros(4)
    u = np.linspace(0.0, 1.0, 50001)
    lam = np.asarray(_sample(GRID, p, u))
    assert np.all(np.diff(lam) >= 0.0)
    # The gap p[20:30] = 0 covers the open interval (GRID[20], GRID[29]).
    assert not np.any((lam > GRID[20]) & (lam < GRID[29]))
    # u = 0 and u = 1 map to the ends of the support.
    assert lam[0] == GRID[2] and lam[-1] == GRID[-5]


def test_chi_square_of_sampled_wavelengths_against_the_pdf():
    p = _density_with_zeros(5)
    rng = np.random.default_rng(12345)
    n = 200_000
    lam = np.asarray(_sample(GRID, p, rng.random(n)))
    # Bins: every segment split in two, expected counts from the exact CDF.
    edges = np.unique(np.concatenate([GRID, 0.5 * (GRID[1:] + GRID[:-1])]))
    expected = n * np.diff(np.asarray(_invert(GRID, p, edges)))
    observed = np.histogram(lam, bins=edges)[0]
    keep = expected > 5.0
    assert observed[~keep].sum() == 0 or expected[~keep].sum() > 0
    chi2 = np.sum((observed[keep] - expected[keep]) ** 2 / expected[keep])
    dof = int(keep.sum()) - 1
    pvalue = scipy.stats.chi2.sf(chi2, dof)
    assert pvalue > 1e-3, f"chi2={chi2:.1f} dof={dof} p={pvalue:.2e}"


@pytest.mark.parametrize(
    "p0,p1",
    [
        (1.0, 1.0),  # flat: t = r / p0
        (1.0, 1.0 + 1e-15),  # slope ~ 0: no cancellation
        (0.0, 1.0),  # rising from zero: t = sqrt(2 r / s)
        (1.0, 0.0),  # falling to zero
        (1e-300, 1.0),  # denormal-scale start
        (1.0, 1e-12),
    ],
)
def test_degenerate_segments_round_trip(p0, p1):
    grid = np.array([0.0, 1.0])
    p = np.array([p0, p1])
    u = np.linspace(0.0, 1.0, 4001)
    lam = np.asarray(_sample(grid, p, u))
    back = np.asarray(_invert(grid, p, lam))
    assert np.max(np.abs(back - u)) < 1e-12
    assert np.all((lam >= 0.0) & (lam <= 1.0))
    # Analytic inverses: CDF p0 t + s t^2 / 2 = u after normalization.
    pn = np.asarray(sampling.normalize(grid, p))
    s = pn[1] - pn[0]
    if abs(s) < 1e-9:
        np.testing.assert_allclose(lam, u / pn[0], atol=1e-12)
    else:
        want = (-pn[0] + np.sqrt(np.maximum(pn[0] ** 2 + 2.0 * s * u, 0.0))) / s
        np.testing.assert_allclose(lam, want, atol=1e-7)


def test_scale_of_the_density_does_not_matter():
    p = _density_with_zeros(6)
    u = np.linspace(0.0, 1.0, 1001)
    base = np.asarray(_sample(GRID, p, u))
    for scale in (1e-200, 1e-30, 1e30, 1e200):
        got = np.asarray(_sample(GRID, p * scale, u))
        # (at u = 1 the end of a falling segment is ill-conditioned: dlambda/du = 1/p -> inf)
        assert np.max(np.abs(got - base)[:-1]) < 1e-9, scale
        assert abs(got[-1] - base[-1]) < 1e-5, scale


def test_gradients_of_sample_are_finite_and_match_finite_differences():
    p = _density_with_zeros(7) + 0.0
    u = jnp.asarray(np.linspace(0.01, 0.99, 37))
    f = jax.jit(lambda q: jnp.sum(jnp.sin(sampling.sample(GRID, q, u) / 20.0)))
    g = np.asarray(jax.jit(jax.grad(f))(jnp.asarray(p)))
    assert np.all(np.isfinite(g))
    rng = np.random.default_rng(0)
    d = rng.normal(size=p.size) * (p > 0)  # stay inside the support's sign pattern
    h = 1e-6
    fd = (float(f(jnp.asarray(p + h * d))) - float(f(jnp.asarray(p - h * d)))) / (2 * h)
    assert abs(fd - g @ d) <= 1e-5 * max(1.0, abs(fd)), (fd, g @ d)
    gu = np.asarray(jax.jit(jax.vmap(jax.grad(lambda x: sampling.sample(GRID, p, x))))(u))
    # dlambda/du = 1 / p(lambda)
    want = 1.0 / np.asarray(_pdf(GRID, p, _sample(GRID, p, u)))
    np.testing.assert_allclose(gu, want, rtol=1e-8)


def test_sample_four_and_mixture_pdf():
    P = np.stack([_density_with_zeros(s) for s in range(4)])
    u = np.linspace(0.0, 1.0, 101)
    lam = np.asarray(jax.jit(sampling.sample_four)(GRID, P, u))
    assert lam.shape == (4, 101)
    for k in range(4):
        np.testing.assert_allclose(lam[k], np.asarray(_sample(GRID, P[k], u)), rtol=0, atol=1e-11)
    x = np.linspace(380.0, 780.0, 333)
    want = np.mean([np.asarray(_pdf(GRID, P[k], x)) for k in range(4)], axis=0)
    np.testing.assert_allclose(np.asarray(jax.jit(sampling.mixture_pdf)(GRID, P, x)), want, rtol=1e-15)
    np.testing.assert_allclose(np.asarray(jax.jit(sampling.balance_estimate_weights)(GRID, P, x[want > 0])),
                               1.0 / (4.0 * want[want > 0]), rtol=1e-14)


def test_stratified_uniform_triple():
    u = np.linspace(0.0, 1.0, 1001, endpoint=False)
    lam = np.asarray(sampling.sample_stratified_uniform(380.0, 780.0, u))
    assert lam.shape == (4, u.size)
    # The four wavelengths are a quarter of the range apart (mod the range).
    gaps = np.mod(np.diff(lam, axis=0), 400.0)
    np.testing.assert_allclose(gaps, 100.0, atol=1e-9)
    for j in range(4):
        back = np.asarray(sampling.invert_stratified_uniform(380.0, 780.0, lam[j], j))
        np.testing.assert_allclose(np.mod(back - u + 0.5, 1.0) - 0.5, 0.0, atol=1e-12)
    assert float(sampling.pdf_stratified_uniform(380.0, 780.0, 500.0)) == 1.0 / 400.0
    assert float(sampling.pdf_stratified_uniform(380.0, 780.0, 800.0)) == 0.0
    table = np.asarray(sampling.stratified_uniform_table(GRID))
    np.testing.assert_allclose(np.trapezoid(table, GRID, axis=1), 1.0, rtol=1e-14)
