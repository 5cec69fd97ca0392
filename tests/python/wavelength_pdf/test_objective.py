"""The objective J of design §4: exact target, refinement-stable quadrature, gradients,
extremes (scale, a 2 nm line, long zero stretches) and the stratified-uniform baseline.

All fixtures use one 21-node grid and spectra whose nodes fit one padding class, so the
jitted objective compiles once for the whole file.
"""

import colour
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import colorimetry, init, objective, quadrature, sampling, uniform
from wavelength_pdf import problem as problem_mod
from wavelength_pdf.problem import make_problem
from wavelength_pdf.spectra import Spectrum

from brute_force import assert_gradient_matches_finite_differences, lamp_colour, table_colours

GRID = np.arange(380.0, 781.0, 20.0)  # 21 nodes


def _spectrum(name, wl, val):
    return Spectrum(name=name, source=f"test:{name}", wavelengths=np.asarray(wl, float),
                    values=np.asarray(val, float))


def smooth():
    wl = np.arange(370.0, 791.0, 5.0)
    return _spectrum("smooth", wl, 1.0 + 0.6 * np.sin(wl / 37.0) + (wl - 370.0) / 300.0)


def spiky():
    """Weak continuum plus three lines of ~2 nm FWHM, sampled every 1 nm."""
    wl = np.arange(380.0, 781.0, 1.0)
    val = 0.05 + sum(a * np.exp(-0.5 * ((wl - c) / 0.9) ** 2) for c, a in [(436, 1.0), (546, 1.6), (611, 2.0)])
    return _spectrum("spiky", wl, val)


def line_2nm():
    """A 2 nm triangular line between the grid nodes 420 and 440: zero at every node."""
    return _spectrum("line", [432.0, 433.0, 434.0], [0.0, 1.0, 0.0])


def zero_stretch():
    """Non-zero on 380-450 and 650-780 nm only."""
    wl = np.array([380.0, 450.0, 450.5, 649.5, 650.0, 780.0])
    return _spectrum("gaps", wl, [1.0, 2.0, 0.0, 0.0, 1.5, 0.5])


def random_table(seed=0, support=None):
    rng = np.random.default_rng(seed)
    P = rng.uniform(0.2, 1.0, (4, GRID.size))
    if support is not None:
        P = np.where(support[None, :], P, 0.0)
    return P


_cmf_wl, _cmf = colorimetry.cmfs()


def brute_force(spectrum, P, n=100_000, uniform=False):
    """J, E[C] and std(C) from a fine midpoint rule in u, written independently of the
    objective: NumPy interpolation of the spectrum and colour-science's CIELAB/CIEDE2000."""
    lo, hi = GRID[0], GRID[-1]
    f, c = lamp_colour(spectrum, lo, hi)
    u = (np.arange(n) + 0.5) / n
    if uniform:
        lam = np.asarray(sampling.sample_stratified_uniform(lo, hi, u))
        C = (hi - lo) / 4.0 * np.sum(f(lam), axis=0)
    else:
        C = table_colours(f, GRID, P, u)
    C, c = C / c[1], c / c[1]
    white = colour.XYZ_to_xy(colorimetry.white_d65())
    dE = colour.delta_E(colour.XYZ_to_Lab(C, white), colour.XYZ_to_Lab(c, white), method="CIE 2000")
    return float(np.mean(dE)), C.mean(axis=0), C.std(axis=0), c


@pytest.fixture(scope="module")
def problems():
    return {s.name: make_problem(s, GRID) for s in (smooth(), spiky(), line_2nm(), zero_stretch())}


def test_all_fixtures_share_one_compiled_shape(problems):
    sizes = {p.nodes.size for p in problems.values()}
    assert len(sizes) == 1 and sizes.pop() % problem_mod._PAD == 0


def test_target_is_the_exact_integral_with_Y_one(problems):
    # A flat spectrum: c is the integral of the CMFs, exact by the trapezoid rule on their
    # 1 nm nodes (they are linear in between).
    flat = make_problem(_spectrum("flat", [300.0, 900.0], [3.0, 3.0]), GRID)
    sel = (_cmf_wl >= GRID[0]) & (_cmf_wl <= GRID[-1])
    want = np.trapezoid(_cmf[sel], _cmf_wl[sel], axis=0)
    np.testing.assert_allclose(flat.c, want / want[1], rtol=1e-13)
    for p in problems.values():
        assert p.c[1] == 1.0
        np.testing.assert_allclose(objective.target(p), p.c)
    # The product of two piecewise-linear functions, against a fine midpoint rule.
    _, _, _, c_bf = brute_force(spiky(), random_table(), n=10)
    np.testing.assert_allclose(problems["spiky"].c, c_bf, rtol=1e-8)


@pytest.mark.parametrize("name", ["smooth", "spiky"])
def test_J_matches_an_independent_brute_force_integral(problems, name):
    p = problems[name]
    spectrum = smooth() if name == "smooth" else spiky()
    P = random_table(1)
    J_bf, mean_bf, std_bf, c_bf = brute_force(spectrum, P)
    J = objective.J(p, P)
    assert abs(J - J_bf) < 2e-4 * J_bf, f"J {J} vs brute force {J_bf}"
    # The quadrature's moments agree with the brute force ones too.
    _, m1, m2 = objective.moments(p, P)
    np.testing.assert_allclose(m1, p.c, rtol=1e-9)
    np.testing.assert_allclose(mean_bf, c_bf, rtol=1e-4)
    std = np.sqrt(m2 - (m1 - p.c) ** 2)
    np.testing.assert_allclose(std, std_bf, rtol=2e-3)


@pytest.mark.parametrize("name,tol", [("smooth", 3e-5), ("spiky", 3e-5), ("line", 2e-3), ("gaps", 2e-4)])
def test_J_does_not_change_when_the_u_grid_is_refined(problems, name, tol):
    p = problems[name]
    support = init.support_nodes(p)
    P = random_table(2, support)
    J, J_fine = objective.J_pair(p, P)
    J8 = objective.J(p, P, 8)
    assert np.isfinite(J) and J > 0
    # What is left comes from CIEDE2000 itself, at places no breakpoint knows: it jumps
    # where the hue of C(u) crosses the opposite of the target's (the hue-mean branch,
    # Sharma et al. 2005) and has a cone point where C(u) passes through c. Random tables
    # make C(u) wander round the hue circle; a single line makes C(u) sweep straight
    # through c (every estimate has the line's chromaticity).
    assert abs(J - J8) <= 3 * tol * J8 and abs(J_fine - J8) <= tol * J8, (J, J_fine, J8)


def test_mean_of_the_estimator_is_the_target(problems):
    for p in problems.values():
        P = random_table(3, init.support_nodes(p))
        _, m1, _ = objective.moments(p, P)
        np.testing.assert_allclose(m1, p.c, rtol=1e-9, err_msg=p.name)
        _, m1u, _ = uniform.uniform_moments(p)
        np.testing.assert_allclose(m1u, p.c, rtol=1e-9, err_msg=p.name)


def test_estimate_agrees_with_the_quadrature(problems):
    p = problems["spiky"]
    P = jnp.asarray(random_table(4))
    glx, glw = quadrature.gauss_legendre(quadrature.ORDER)
    u, wt, C, _ = jax.jit(quadrature.table_quadrature)(P, p.arrays, glx, glw)
    sel = np.linspace(0, u.size - 1, 500).astype(int)
    np.testing.assert_allclose(objective.estimate(p, P, np.asarray(u)[sel]), np.asarray(C)[sel], rtol=1e-10)
    assert abs(float(jnp.sum(wt)) - 1.0) < 1e-12


def test_gradient_matches_finite_differences(problems):
    p = problems["smooth"]
    P = random_table(5)
    g = assert_gradient_matches_finite_differences(objective.value_and_grad(p), P)
    # J does not depend on the scale of a density: the gradient is orthogonal to it.
    for k in range(4):
        assert abs(np.sum(g[k] * P[k])) < 1e-8 * np.linalg.norm(g[k]) * np.linalg.norm(P[k])


def test_scale_invariance_from_1e_minus_30_to_1e30(problems):
    base = problems["spiky"]
    P = random_table(6)
    J0 = objective.J(base, P)
    s = spiky()
    for scale in (1e-30, 1e-10, 1e10, 1e30):
        p = make_problem(_spectrum("spiky", s.wavelengths, s.values * scale), GRID)
        np.testing.assert_allclose(p.spec, base.spec, rtol=1e-14)
        np.testing.assert_allclose(p.c, base.c, rtol=1e-14)
        assert abs(objective.J(p, P) - J0) <= 1e-12 * J0, scale
        assert p.scale * scale == pytest.approx(base.scale, rel=1e-12)


def test_a_single_2nm_line_between_nodes(problems):
    p = problems["line"]
    P0 = init.equal_mass_partition(p)
    # Every density puts its mass on the two nodes around the line (420 and 440 nm).
    around = (GRID == 420.0) | (GRID == 440.0)
    assert np.all(P0[:, around] > 0) and np.all(P0[:, ~around] == 0)
    J, J_fine = objective.J_pair(p, P0)
    assert np.isfinite(J) and abs(J - J_fine) < 2e-3 * J
    _, m1, m2 = objective.moments(p, P0)
    np.testing.assert_allclose(m1, p.c, rtol=1e-9)
    assert np.all(np.isfinite(m2))
    g = np.asarray(objective.value_and_grad(p)(P0)[1])
    assert np.all(np.isfinite(g))


def test_long_zero_stretches_and_exact_zeros_in_the_table(problems):
    p = problems["gaps"]
    support = init.support_nodes(p)
    assert not np.all(support)  # nodes inside the gap see no light
    P = random_table(7, support)
    assert np.any(P == 0.0)
    J, J_fine = objective.J_pair(p, P)
    assert np.isfinite(J) and abs(J - J_fine) <= 2e-4 * J
    g = np.asarray(objective.value_and_grad(p)(P)[1])
    assert np.all(np.isfinite(g))
    _, m1, _ = objective.moments(p, P)
    np.testing.assert_allclose(m1, p.c, rtol=1e-9)


def test_uniform_is_the_balance_heuristic_with_four_uniform_densities(problems):
    p = problems["smooth"]
    s = smooth()
    lo, hi = GRID[0], GRID[-1]
    u = np.linspace(0.0, 1.0, 1001, endpoint=False)
    lam = np.asarray(sampling.sample_stratified_uniform(lo, hi, u))
    # (hi - lo)/4 * sum_j f(lambda_j), computed directly ...
    f = np.interp(lam, s.wavelengths, s.values)[..., None] * np.stack(
        [np.interp(lam, _cmf_wl, _cmf[:, i]) for i in range(3)], axis=-1) * p.scale
    direct = (hi - lo) / 4.0 * f.sum(axis=0)
    np.testing.assert_allclose(uniform.uniform_estimate(p, u), direct, rtol=1e-12)
    # ... and J against the independent brute force integral.
    J_bf = brute_force(s, None, uniform=True)[0]
    assert abs(uniform.uniform_J(p) - J_bf) < 2e-4 * J_bf


def test_stratified_uniform_equals_four_quarter_boxes():
    """Four box densities, one per quarter of the range, sharing u, give the same J as
    stratified uniform sampling: the set of four wavelengths has the same distribution."""
    lo, hi, d = 380.0, 780.0, 1e-4
    cuts = [480.0, 580.0, 680.0]
    grid = np.unique(np.concatenate([[lo, hi, 405, 455, 505, 555, 605, 655, 430, 530, 630, 730],
                                     [c + e for c in cuts for e in (-d, 0.0, d)]]))
    assert grid.size == GRID.size  # same compiled shape as the other tests
    edges = [lo] + cuts + [hi]
    P = np.stack([((grid >= edges[k] - 1e-12) & (grid <= edges[k + 1] + 1e-12)).astype(float) for k in range(4)])
    p = make_problem(smooth(), grid)
    Ju = uniform.uniform_J(p)
    Jb = objective.J(p, P)
    assert abs(Jb - Ju) < 2e-3 * Ju, (Jb, Ju)


def test_bad_input_is_rejected_with_the_source_named():
    with pytest.raises(ValueError, match="test:dark"):
        make_problem(_spectrum("dark", [300.0, 350.0], [1.0, 1.0]), GRID)
    with pytest.raises(ValueError, match="strictly increasing"):
        make_problem(smooth(), GRID[::-1])
    with pytest.raises(ValueError, match="shape"):
        objective.J(make_problem(smooth(), GRID), np.ones((3, GRID.size)))
