"""Estimator health: exact bias, per-channel std, and the acceptance rule."""

import re

import jax
import numpy as np
import pytest

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import colorimetry, health, init, sampling, second_moment
from wavelength_pdf.problem import make_problem
from wavelength_pdf.spectra import Spectrum

GRID = np.arange(380.0, 781.0, 20.0)  # the same compiled shape as test_objective
_cmf_wl, _cmf = colorimetry.cmfs()


def _smooth():
    wl = np.arange(370.0, 791.0, 5.0)
    return Spectrum("smooth", "test:smooth", wl, 1.0 + 0.6 * np.sin(wl / 37.0) + (wl - 370.0) / 300.0)


@pytest.fixture(scope="module")
def problem():
    return make_problem(_smooth(), GRID)


def _f(lam, spectrum, scale):
    spec = np.interp(lam, spectrum.wavelengths, spectrum.values, left=0.0, right=0.0)
    cmf = np.stack([np.interp(lam, _cmf_wl, _cmf[:, i], left=0.0, right=0.0) for i in range(3)], axis=-1)
    return scale * spec[..., None] * cmf


def _integral_of_f(a, b, spectrum, scale, n=200_001):
    x = np.unique(np.concatenate([np.linspace(a, b, n), _cmf_wl[(_cmf_wl > a) & (_cmf_wl < b)]]))
    mid = 0.5 * (x[1:] + x[:-1])
    return np.sum(_f(mid, spectrum, scale) * np.diff(x)[:, None], axis=0)


def test_the_initialization_is_unbiased_and_accepted(problem):
    P0 = init.equal_mass_partition(problem)
    h0 = health.health(problem, P0)
    assert h0.bias < 1e-12
    assert np.all(h0.missing_mass == 0.0)
    assert np.all(np.isfinite(h0.std)) and np.all(h0.std > 0)
    assert h0.accepted(h0) and h0.reason(h0) == ""
    assert h0.bias_rel == h0.bias and np.array_equal(h0.std_rel, h0.std)


def test_bias_is_exactly_the_mass_where_the_mixture_is_zero(problem):
    P = np.ones((4, GRID.size))
    gap = (GRID >= 600.0) & (GRID <= 700.0)
    P[:, gap] = 0.0  # the mixture is zero on [600, 700] nm, where f > 0
    h = health.health(problem, P)
    lost = _integral_of_f(600.0, 700.0, _smooth(), problem.scale) / problem.c
    np.testing.assert_allclose(-h.bias_xyz, lost, rtol=1e-7)
    np.testing.assert_allclose(h.missing_mass, lost, rtol=1e-7)
    assert h.bias > health.MAX_BIAS
    assert not h.accepted() and "bias" in h.reason()


def test_std_matches_a_brute_force_estimate(problem):
    rng = np.random.default_rng(3)
    P = rng.uniform(0.2, 1.0, (4, GRID.size))
    h = health.health(problem, P)
    n = 400_000
    u = (np.arange(n) + 0.5) / n
    lam = np.asarray(jax.jit(sampling.sample_four)(GRID, P, u))
    m = 4.0 * np.asarray(jax.jit(sampling.mixture_pdf)(GRID, P, lam))
    C = np.sum(_f(lam, _smooth(), problem.scale) / m[..., None], axis=0)
    np.testing.assert_allclose(h.std, C.std(axis=0) / problem.c, rtol=2e-3)


def test_fireflies_are_rejected_against_the_initialization(problem):
    P0 = init.equal_mass_partition(problem)
    h0 = health.health(problem, P0)
    # A table that keeps a tiny density where f is not small: unbiased, but C(u) is huge
    # on a tiny u-interval. J barely notices; the std does.
    P = np.ones((4, GRID.size))
    P[:, (GRID >= 600.0) & (GRID <= 700.0)] = 1e-7
    h = health.health(problem, P)
    assert h.bias <= health.MAX_BIAS
    assert np.max(h.std / h0.std) > 100  # X and Y see 600-700 nm, Z hardly
    assert not h.accepted(h0)
    assert "std/c worse" in h.reason(h0)


def test_zero_mixture_at_a_node_where_f_is_positive_gives_infinite_variance(problem):
    P = np.ones((4, GRID.size))
    P[:, GRID == 600.0] = 0.0  # a single node: no bias, but f / M ~ 1 / |lambda - 600|
    h = health.health(problem, P)
    assert h.bias < 1e-12
    assert not np.all(np.isfinite(h.std)) or np.all(h.std > 1e3)
    assert not h.accepted()


def test_exact_second_moment_matches_fine_quadrature(problem):
    rng = np.random.default_rng(4)
    P = rng.uniform(0.0, 1.0, (4, GRID.size))
    P[:, 5] = 1e-4  # a near-zero mixture value makes 1/M vary a lot over two segments
    PN = P / np.trapezoid(P, GRID, axis=1)[:, None]
    M = PN.sum(axis=0)
    got = np.asarray(jax.jit(second_moment.diag_second_moment)(problem.arrays, M))
    # Fine midpoint rule, graded towards 480 nm where 1/M varies on a 1e-3 nm scale.
    graded = 480.0 + np.array([-1.0, 1.0])[:, None] * np.geomspace(1e-9, 20.0, 20000)[None, :]
    x = np.unique(np.concatenate([np.linspace(380.0, 780.0, 400_001), graded.ravel(),
                                  _cmf_wl[(_cmf_wl > 380) & (_cmf_wl < 780)]]))
    mid = 0.5 * (x[1:] + x[:-1])
    want = np.sum(_f(mid, _smooth(), problem.scale) ** 2 / np.interp(mid, GRID, M)[:, None]
                  * np.diff(x)[:, None], axis=0)
    np.testing.assert_allclose(got, want, rtol=1e-7)


def test_uniform_health(problem):
    hu = health.uniform_health(problem)
    assert hu.bias < 1e-12 and np.all(np.isfinite(hu.std))


def test_a_channel_whose_integral_is_zero_is_unbiased_not_nan():
    """A red line (z-bar is 0 above ~650 nm) has Z = 0: its relative bias and std were 0 / 0,
    NaN, and every table for it was refused as 'relative bias nan'."""
    red = Spectrum("red line", "test:red", np.array([699.0, 700.0, 701.0]), np.array([0.0, 1.0, 0.0]))
    p = make_problem(red, GRID)
    assert p.c[2] == 0.0
    P0 = init.equal_mass_partition(p)
    h = health.health(p, P0)
    assert np.all(np.isfinite(h.bias_xyz)) and np.all(np.isfinite(h.std)), (h.bias_xyz, h.std)
    assert h.bias_xyz[2] == 0.0 and h.std[2] == 0.0
    assert h.bias < 1e-9
    assert health.rejection(h, h) == ""
    u = health.uniform_health(p)
    assert np.all(np.isfinite(u.std)) and u.std[2] == 0.0


def test_rejection_never_writes_nan():
    h = health.Health(bias=float("nan"), bias_xyz=np.full(3, np.nan), std=np.zeros(3),
                      missing_mass=np.zeros(3))
    reason = health.rejection(h)
    assert reason and not re.search(r"\bnan\b", reason, re.IGNORECASE), reason
    ok = health.Health(bias=0.0, bias_xyz=np.zeros(3), std=np.zeros(3), missing_mass=np.zeros(3))
    assert not re.search(r"\bnan\b", health.rejection(ok, None, J=float("nan"), J_uniform=1.0), re.IGNORECASE)
