"""The ``stratified`` objective of design §4.6: the linearised CIEDE2000 of a pixel's mean of
N stratified samples of C(u), against an independent computation from C(u) tabulated on a
fine grid of u (NumPy and colour-science); its gradient against finite differences; J kept
by name; bad names and sample counts refused before any work.
"""

import colour
import numpy as np
import pytest

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import colorimetry, init, objective, uniform
from wavelength_pdf import problem as problem_mod
from wavelength_pdf.optimize import evaluate_table
from wavelength_pdf.problem import make_problem, with_objective
from wavelength_pdf.result import Result
from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.table import Table

from brute_force import assert_gradient_matches_finite_differences, lamp_colour, table_colours

GRID = np.arange(380.0, 781.0, 20.0)  # 21 nodes
#: Cells of the fine u grid of the independent computation (every N below divides it).
CELLS = 2 ** 16


def spiky():
    """Weak continuum plus three lines of ~2 nm FWHM, sampled every 1 nm."""
    wl = np.arange(380.0, 781.0, 1.0)
    val = 0.05 + sum(a * np.exp(-0.5 * ((wl - c) / 0.9) ** 2) for c, a in [(436, 1.0), (546, 1.6), (611, 2.0)])
    return Spectrum(name="spiky", source="test:spiky", wavelengths=wl, values=val)


def random_table(seed):
    return np.random.default_rng(seed).uniform(0.2, 1.0, (4, GRID.size))


_white = colour.XYZ_to_xy(colorimetry.white_d65())


def _lab(xyz):
    return colour.XYZ_to_Lab(xyz, _white)


def path_colours(spectrum, P):
    """C(u) at the midpoints of CELLS equal cells of u and the target c (Y = 1), from the
    sampler and the mixture density alone (not the objective's quadrature)."""
    f, c = lamp_colour(spectrum, GRID[0], GRID[-1])
    C = table_colours(f, GRID, P, (np.arange(CELLS) + 0.5) / CELLS)
    return C / c[1], c / c[1]


def linearised_de2(C, c, n):
    """E[CIEDE2000^2] of the mean of n stratified samples, linearised: the mean's XYZ
    covariance (per-stratum covariances / n^2) through Lab's Jacobian (central differences)
    into CIEDE2000's second derivative along the covariance's principal axes."""
    S = C.reshape(n, -1, 3)
    d = S - S.mean(axis=1, keepdims=True)
    cov = np.einsum("smi,smj->ij", d, d) / S.shape[1] / n ** 2
    h = 1e-6
    Jl = np.stack([(_lab(c + h * e) - _lab(c - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    s, V = np.linalg.eigh(Jl @ cov @ Jl.T)
    lab_c, eps = _lab(c), 1e-3
    q = [0.5 * sum(colour.delta_E(lab_c + g * eps * v, lab_c, method="CIE 2000") ** 2 for g in (1, -1)) / eps ** 2
         for v in V.T]
    return float(np.dot(np.clip(s, 0, None), q))


@pytest.fixture(scope="module")
def lamp():
    return make_problem(spiky(), GRID)


@pytest.mark.parametrize("n", [1, 4, 64])
def test_value_is_the_linearised_error_of_a_stratified_pixel(lamp, n):
    P = random_table(1)
    C, c = path_colours(spiky(), P)
    want = linearised_de2(C, c, n)
    got = objective.J(with_objective(lamp, "stratified", n), P)
    # The value is sqrt(N E[de^2]): one path's units, as J.
    assert got ** 2 / n == pytest.approx(want, rel=2e-3), (got ** 2 / n, want)


def test_more_strata_never_hurt_and_one_stratum_is_independent_sampling(lamp):
    P = random_table(2)
    C, c = path_colours(spiky(), P)
    values = [objective.J(with_objective(lamp, "stratified", n), P) for n in (1, 2, 8, 32)]
    # N E[de^2] is the mean within-stratum variance (in CIEDE2000's metric), which refining
    # nested strata only lowers.
    assert all(b <= a * (1 + 1e-9) for a, b in zip(values, values[1:])), values
    assert values[0] ** 2 == pytest.approx(linearised_de2(C, c, 1), rel=2e-3)


def test_gradient_matches_finite_differences(lamp):
    assert_gradient_matches_finite_differences(objective.value_and_grad(with_objective(lamp, "stratified", 16)),
                                               random_table(3))


def test_J_stays_available_by_name_and_is_the_default(lamp):
    P = random_table(4)
    plain = objective.J(lamp, P)
    back = with_objective(with_objective(lamp, "stratified", 16), "J")
    assert back.objective == "J" and set(back.arrays) == set(lamp.arrays)
    assert objective.J(back, P) == plain
    assert lamp.objective == "J"
    assert objective.J(with_objective(lamp, "stratified", 16), P) != plain


def test_the_lamps_own_start_beats_uniform_sampling_by_the_pixel_measure(lamp):
    prob = with_objective(lamp, "stratified", 64)
    start = objective.J(prob, init.equal_mass_partition(prob))
    assert start < 0.5 * uniform.uniform_J(prob)


def test_simplify_keeps_the_objective(lamp):
    prob = with_objective(lamp, "stratified", 8)
    simpler = problem_mod.simplify(prob, 1e-3)
    assert simpler.objective == "stratified" and simpler.spp == 8
    P = random_table(5)
    assert objective.J(simpler, P) == pytest.approx(objective.J(prob, P), rel=1e-2)


@pytest.mark.parametrize("name,spp", [("stratifed", 16), ("", 16), ("stratified", 0),
                                      ("stratified", problem_mod.MAX_OBJECTIVE_SPP + 1),
                                      ("stratified", 16.0), ("stratified", True)])
def test_bad_objectives_are_refused(lamp, name, spp):
    with pytest.raises(ValueError):
        with_objective(lamp, name, spp)
    with pytest.raises(ValueError):
        evaluate_table(spiky(), Table(grid=GRID, pdfs=random_table(6)), objective=name, objective_spp=spp)


def test_the_record_names_its_objective_and_reads_it_back():
    r = evaluate_table(spiky(), Table(grid=GRID, pdfs=random_table(7)), objective="stratified", objective_spp=32)
    assert r.objective == "stratified, spp 32"
    assert Result.from_table(r.to_table()).objective == "stratified, spp 32"
    plain = evaluate_table(spiky(), Table(grid=GRID, pdfs=random_table(7)))
    assert plain.objective == "J" and Result.from_table(plain.to_table()).objective == "J"
    # Every figure is the objective's: the table's, the start's and uniform sampling's.
    prob = with_objective(make_problem(spiky(), GRID), "stratified", 32)
    assert r.J == pytest.approx(objective.J(prob, random_table(7)), rel=1e-12)
    assert r.J_init == pytest.approx(objective.J(prob, init.equal_mass_partition(prob)), rel=1e-12)
    assert r.J_uniform == pytest.approx(uniform.uniform_J(prob), rel=1e-12)
    assert r.J_uniform != pytest.approx(plain.J_uniform, rel=1e-3)


def test_with_surface_colours_it_is_the_weighted_mean_over_colours():
    """Design §4.5 and §4.6: each colour's value at its own target, weighted; here against
    the colours' C(u) tabulated by the estimator (not the quadrature) on a fine grid of u."""
    from wavelength_pdf import predict
    from wavelength_pdf.reflectances import ReflectanceSet

    wl = np.array([380.0, 500.0, 600.0, 780.0])
    refl = ReflectanceSet(name="two", source="test", wavelengths=wl,
                          values=np.array([[0.2, 0.3, 0.7, 0.8], [0.9, 0.6, 0.2, 0.1]]),
                          labels=("red", "blue"), weights=np.array([0.25, 0.75]))
    P = random_table(8)
    table = Table(grid=GRID, pdfs=P)
    prob = with_objective(make_problem(spiky(), GRID, refl), "stratified", 8)
    pc = predict.path_colours(table, spiky(), refl, points=CELLS)
    want = sum(w * np.sqrt(8 * linearised_de2(C, c, 8)) for w, C, c in zip(pc.weights, pc.C, pc.target))
    assert objective.J(prob, P) == pytest.approx(want, rel=2e-3)


def test_refine_never_returns_worse_than_the_initialization(lamp):
    """A J search's table worse than the start by the chosen objective (here a random table
    standing for it) is polished, and the initialization polished too: the result is never
    worse than the start by that objective, and is accepted by the health rules."""
    from wavelength_pdf import health, solvers
    from wavelength_pdf.budget import Budget

    prob = with_objective(lamp, "stratified", 16)
    P0 = init.equal_mass_partition(prob)
    start = solvers.Start.of(prob, P0)
    bad = random_table(9)
    assert objective.J(prob, bad) > start.J
    out = solvers.refine(start, solvers.SolverResult(P=bad, J=objective.J(lamp, bad), nfev=7), Budget(20))
    assert out.J <= start.J * (1 + 1e-12)
    assert out.J == pytest.approx(objective.J(prob, out.P), rel=1e-12)
    assert health.health(prob, out.P).accepted(start.health)
    assert out.nfev > 7
