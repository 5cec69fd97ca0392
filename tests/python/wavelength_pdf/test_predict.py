"""The predictions of a table's pixel error (wavelength_pdf.predict)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from wavelength_pdf import objective
from wavelength_pdf.problem import make_problem
from wavelength_pdf import predict as P
from wavelength_pdf import stratified
from wavelength_pdf.spectra import Spectrum, load_spectrum


def _line(centre: float = 550.0, half: float = 0.2) -> Spectrum:
    return Spectrum("line", "test", np.array([380.0, centre - half, centre, centre + half, 780.0]),
                    np.array([0.0, 0.0, 1.0, 0.0, 0.0]))


@pytest.fixture(scope="module")
def d65() -> Spectrum:
    return load_spectrum("cie:D65", 380.0, 780.0)


@pytest.fixture(scope="module")
def fl2() -> Spectrum:
    return load_spectrum("cie:FL2", 380.0, 780.0)


def test_padded_table_is_the_same_densities(fl2):
    t = stratified.stratified_table(fl2, "spd", 380.0, 780.0)
    p = P.padded(t, fl2.wavelengths)
    assert p.grid.size % P.GRID_CLASS == 0 and p.grid.size >= t.grid.size
    assert np.all(np.isin(t.grid, p.grid))
    lam = np.random.default_rng(1).uniform(380.0, 780.0, 5000)
    for k in range(4):
        np.testing.assert_allclose(np.interp(lam, p.grid, p.pdfs[k]), np.interp(lam, t.grid, t.pdfs[k]),
                                   rtol=1e-12, atol=1e-15)


def test_a_line_sampled_in_proportion_is_exact_and_uniform_is_not():
    """Under one narrow line, a table whose mixture is the lamp's shape (spd) sends all four
    wavelengths into the line with weights that cancel the lamp: C(u) varies only with the
    CMFs across 0.4 nm, so every prediction is ~0 (below 0.01, a tenth of a just noticeable
    difference squared; J, one path's error, the largest). The uniform table covers the line
    too (unbiased) but lands in it rarely: an error a million times larger. (Covering the
    line is not enough for a small error.)"""
    line = _line()
    spd = P.path_colours(stratified.stratified_table(line, "spd", 380.0, 780.0), line)
    uni = P.path_colours(stratified.uniform_table(380.0, 780.0), line)
    for name, fn in P.CANDIDATES.items():
        for ps in P.PIXEL_SAMPLERS:
            e_spd, e_uni = fn(spd, 16, ps), fn(uni, 16, ps)
            assert e_spd < 1e-2, (name, ps, e_spd)
            assert e_uni > 1e6 * e_spd, (name, ps, e_uni, e_spd)


@pytest.mark.parametrize("row", ["uniform", "spd"])
def test_predictions_do_not_depend_on_the_lamps_power(fl2, row):
    table = stratified.uniform_table(380.0, 780.0) if row == "uniform" else \
        stratified.stratified_table(fl2, "spd", 380.0, 780.0)
    brighter = Spectrum("x", "test", fl2.wavelengths, 1000.0 * fl2.values)
    a, b = P.path_colours(table, fl2), P.path_colours(table, brighter)
    for name, fn in P.CANDIDATES.items():
        for ps in P.PIXEL_SAMPLERS:
            np.testing.assert_allclose(fn(a, 64, ps), fn(b, 64, ps), rtol=1e-8, err_msg=name)


def test_stratified_mean_falls_faster_than_independent(d65):
    """Independent samples: the mean's covariance is Var/N, so 16 -> 64 spp divides it by 4
    exactly; stratified, C(u) is smooth inside most strata and it falls much faster."""
    pc = P.path_colours(stratified.uniform_table(380.0, 780.0), d65)
    ind = P.covariance_de2(pc, 16, "independent") / P.covariance_de2(pc, 64, "independent")
    strat = P.covariance_de2(pc, 16, "sobol") / P.covariance_de2(pc, 64, "sobol")
    np.testing.assert_allclose(ind, 4.0, rtol=1e-9)
    assert strat > 10.0


def _monte_carlo(problem, table, spp, ps, sets, seed):
    """Lab and CIEDE2000 squared errors of the mean of spp samples of C(u) with u drawn
    continuously (the objective's estimator at random u, not the prediction's grid)."""
    rng = np.random.default_rng(seed)
    if ps == "sobol":
        u = (np.arange(spp)[None, :] + rng.random((sets, spp))) / spp
    else:
        u = rng.random((sets, spp))
    C = objective.estimate(problem, table.pdfs, u.ravel()).reshape(sets, spp, 3).mean(axis=1)
    lab_c = P.lab(objective.target(problem))
    lab = P.lab(C)
    return np.sum((lab - lab_c) ** 2, axis=1), P.delta_e2000(lab, lab_c[None]) ** 2


@pytest.mark.parametrize("ps, metrics", [("sobol", ("lab", "de2000")), ("independent", ("lab",))])
def test_linearised_covariance_agrees_with_monte_carlo(d65, fl2, ps, metrics):
    """The linearised Lab covariance (and its CIEDE2000 form) of the mean of 64 samples
    against a Monte Carlo of it, within 4 standard errors plus 3 % for the linearisation.
    Stratified, the errors are small (~0.1 Lab units) and both forms hold. Independent, they
    are ~4 units around a near-grey colour, where CIEDE2000 is far from its local quadratic
    form (its chroma weighting grows with the sample's own chroma: the linearised form
    overestimates by a third, measured), so only Lab is checked there."""
    for lamp in (d65, fl2):
        table = stratified.stratified_table(lamp, "xyz", 380.0, 780.0)
        problem = make_problem(lamp, grid=table.grid)
        pc = P.path_colours(table, lamp)
        lab2, de2 = _monte_carlo(problem, table, 64, ps, 3000, 7)
        for metric in metrics:
            sample = lab2 if metric == "lab" else de2
            pred = P.covariance_de2(pc, 64, ps, metric)
            se = sample.std(ddof=1) / np.sqrt(sample.size)
            assert abs(pred - sample.mean()) < 4 * se + 0.03 * sample.mean(), (lamp.name, metric, pred,
                                                                               sample.mean(), se)


def test_stratified_candidate_agrees_with_continuous_monte_carlo(fl2):
    """Candidate (b) draws u from the fine grid's cells; a continuous draw gives the same
    expected squared CIEDE2000 within the two estimates' noise."""
    table = stratified.uniform_table(380.0, 780.0)
    problem = make_problem(fl2, grid=table.grid)
    pc = P.path_colours(table, fl2)
    _, de2 = _monte_carlo(problem, table, 16, "sobol", 3000, 3)
    pred = P.stratified_de2(pc, 16, "sobol", sets=8192, seed=5)
    se = de2.std(ddof=1) / np.sqrt(de2.size)
    assert abs(pred - de2.mean()) < 4 * se * np.sqrt(1 + 3000 / 8192), (pred, de2.mean(), se)


def test_j_candidate_is_the_objective(fl2):
    table = stratified.stratified_table(fl2, "luminance", 380.0, 780.0)
    pc = P.path_colours(table, fl2)
    J = objective.J(make_problem(fl2, grid=table.grid), table.pdfs)
    # The padded grid adds u-breakpoints, which moves J only by its quadrature's error.
    np.testing.assert_allclose(np.sqrt(P.j_squared(pc, 16)), J, rtol=1e-4)


def test_unknown_candidate_and_bad_spp(fl2):
    table = stratified.uniform_table(380.0, 780.0)
    with pytest.raises(ValueError, match="unknown candidate"):
        P.predict("nope", table, fl2, 16)
    pc = P.path_colours(table, fl2, points=96)
    with pytest.raises(ValueError, match="divide"):
        P.stratified_de2(pc, 64, "sobol")


@pytest.mark.parametrize("ps", ["sobol", "independent"])
def test_pixel_prediction_is_the_colours_own(fl2, ps):
    """A pixel whose spectrum is sum_b t_b φ_b (the hat basis) is predicted exactly as a
    surface of that reflectance under the lamp (K = 1): the basis' path colours combine
    linearly. Coefficients all 1 are the white surface (the hats sum to 1), and the pixels
    are independent of one another (a stack of them gives each its own value)."""
    lo, hi = 380.0, 780.0
    centres = np.arange(390.0, 780.0, 20.0)
    basis = P.hat_basis(centres, lo, hi)
    np.testing.assert_allclose(basis.values.sum(axis=0), 1.0)
    table = stratified.stratified_table(fl2, "spd", lo, hi)
    pcb = P.path_colours(table, fl2, basis, points=2 ** 12)
    t_col = 0.1 + 0.8 * np.abs(np.sin(centres / 37.0))
    # The surface whose reflectance is the hats' combination, as a one-colour set.
    surface = replace(basis, name="one", values=(t_col @ basis.values)[None], labels=("one",),
                      weights=np.ones(1))
    want = [P.covariance_de2(P.path_colours(table, fl2, None, points=2 ** 12), 64, ps),
            P.covariance_de2(P.path_colours(table, fl2, surface, points=2 ** 12), 64, ps)]
    got = P.pixel_de2(pcb, np.stack([np.ones(centres.size), t_col, 0.5 * t_col]), 64, ps)
    np.testing.assert_allclose(got[:2], want, rtol=1e-6)
    # Half as bright: darker in Lab, so a different but finite and positive error.
    assert np.isfinite(got[2]) and 0 < got[2] != got[1]
    with pytest.raises(ValueError, match="coefficients"):
        P.pixel_de2(pcb, np.ones((2, 3)), 64, ps)


def test_hat_basis_refuses_centres_outside_the_range():
    with pytest.raises(ValueError, match="centres"):
        P.hat_basis([370.0, 500.0], 380.0, 780.0)
    with pytest.raises(ValueError, match="centres"):
        P.hat_basis([500.0, 450.0], 380.0, 780.0)


def test_incoherent_paths_add_the_unstratified_wavelength_noise(fl2):
    """With incoherence r (the paths' magnitude varying from sample to sample), a stratified
    pixel's covariance is Cov_strat + r Cov_indep (pixel_de2's derivation); measured in Lab,
    which is linear in the covariance, the prediction is exactly that sum, per pixel."""
    centres = np.arange(390.0, 780.0, 20.0)
    table = stratified.stratified_table(fl2, "xyz", 380.0, 780.0)
    pcb = P.path_colours(table, fl2, P.hat_basis(centres, 380.0, 780.0), points=2 ** 12)
    t = np.stack([np.ones(centres.size), 0.2 + 0.6 * (centres > 550.0)])
    r = np.array([0.5, 3.0])
    strat = P.pixel_de2(pcb, t, 16, "sobol", "lab")
    indep = P.pixel_de2(pcb, t, 16, "independent", "lab")
    np.testing.assert_allclose(P.pixel_de2(pcb, t, 16, "sobol", "lab", incoherence=r), strat + r * indep,
                               rtol=1e-9)
    assert np.all(indep > 10 * strat)  # stratifying u is what a coherent pixel gains
    # Paths rarer than one in N: the linearisation's limit, r capped at N.
    np.testing.assert_array_equal(P.pixel_de2(pcb, t, 16, "sobol", "lab", incoherence=np.array([16.0, 1e6])),
                                  P.pixel_de2(pcb, t, 16, "sobol", "lab", incoherence=np.array([16.0, 16.0])))
    with pytest.raises(ValueError, match="incoherence"):
        P.pixel_de2(pcb, t, 16, incoherence=np.array([1.0, -1.0]))


def test_one_wavelength_covariance_against_draws_from_the_mixture(fl2):
    """A path that kept one wavelength draws it from the table's mixture q and weights it
    1 / q: the basis' covariance of that estimate, summed over the basis (the white surface),
    against draws of q by its inverse CDF (each of the four densities with probability 1/4,
    wavelength_pdf.sampling); and the mean of those draws is the white surface's colour."""
    from wavelength_pdf import sampling
    from wavelength_pdf.colorimetry import cmfs

    centres = np.arange(390.0, 780.0, 20.0)
    basis = P.hat_basis(centres, 380.0, 780.0)
    table = stratified.stratified_table(fl2, "xyz", 380.0, 780.0)
    M = P.one_wavelength_covariance(table, fl2, basis)
    white_cov = M.sum(axis=(0, 2))
    rng = np.random.default_rng(11)
    n = 400_000
    k = rng.integers(0, 4, n)
    lam = np.empty(n)
    for j in range(4):
        sel = k == j
        lam[sel] = np.asarray(sampling.sample(table.grid, table.pdfs[j], rng.uniform(size=sel.sum())))
    q = np.mean([np.interp(lam, table.grid, p) for p in table.pdfs], axis=0)
    cwl, cval = cmfs()
    cmf = np.stack([np.interp(lam, cwl, cval[:, i]) for i in range(3)], axis=1)
    E = np.interp(lam, fl2.wavelengths, fl2.values)
    fine = np.linspace(380.0, 780.0, 400_001)
    yw = np.trapezoid(np.interp(fine, fl2.wavelengths, fl2.values) * np.interp(fine, cwl, cval[:, 1]), fine)
    g = cmf * (E / q / yw)[:, None]
    assert g[:, 1].mean() == pytest.approx(1.0, rel=0.01)
    np.testing.assert_allclose(np.diag(white_cov), g.var(axis=0), rtol=0.05)


def test_hats_a_line_lamp_does_not_light_are_zero_not_refused():
    """Under a single line most hat functions see no light: the objective would refuse them as
    black surfaces; the basis' path colours give them C = 0 and colour 0, so a white pixel
    (all coefficients 1) is still predicted as the white surface."""
    line = _line(550.0)
    centres = np.arange(390.0, 780.0, 20.0)
    basis = P.hat_basis(centres, 380.0, 780.0)
    table = stratified.stratified_table(line, "spd", 380.0, 780.0)
    with pytest.raises(ValueError, match="reflects nothing"):
        P.path_colours(table, line, basis, points=2 ** 12)
    pcb = P.basis_path_colours(table, line, basis, points=2 ** 12)
    dark = np.abs(centres - 550.0) >= 40.0
    assert np.all(pcb.C[dark] == 0) and np.all(pcb.target[dark] == 0) and np.all(pcb.target[~dark, 1] > 0)
    white = P.covariance_de2(P.path_colours(table, line, None, points=2 ** 12), 16)
    np.testing.assert_allclose(P.pixel_de2(pcb, np.ones((1, centres.size)), 16), [white], rtol=1e-6, atol=1e-12)


def test_path_noise_of_a_grey_pixel_is_its_lightness_noise():
    """The path noise r c c' / N only scales a pixel's colour: for a grey (D65-white-point)
    pixel of luminance Y, in Lab that moves L* = 116 Y^(1/3) - 16 alone, by
    (116 / 3) Y^(1/3) per unit of relative change: E[ΔL*^2] = ((116 / 3) Y^(1/3))^2 r / N.
    r is capped at N, as in pixel_de2."""
    import colour

    from wavelength_pdf.colorimetry import white_d65

    white = np.asarray(white_d65(), dtype=np.float64)
    white = white / white[1]
    Y = np.array([0.2, 0.5, 0.9])
    r = np.array([0.5, 2.0, 100.0])
    got = P.path_de2(Y[:, None] * white[None, :], r, 16, "lab")
    want = ((116.0 / 3.0) * np.cbrt(Y)) ** 2 * np.minimum(r, 16) / 16
    np.testing.assert_allclose(got, want, rtol=1e-5)
    assert colour.XYZ_to_Lab(white * 0.5, P._white_xy())[1:] == pytest.approx([0, 0], abs=1e-6)
