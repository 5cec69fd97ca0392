"""Stratified tables (design §1.7): equal-mass bands of a weight, as ordinary tables."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from wavelength_pdf import sampling, stratified
from wavelength_pdf.cli import main
from wavelength_pdf.model import trapezoid
from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.table import read_table


def _spectrum(wl, val, name="test"):
    return Spectrum(name, f"test:{name}", np.asarray(wl, float), np.asarray(val, float))


LINES = _spectrum(np.arange(380.0, 780.5, 0.5),
                  0.01 + sum(a * np.exp(-0.5 * ((np.arange(380.0, 780.5, 0.5) - c) / 0.7) ** 2)
                             for a, c in ((1.0, 436.0), (3.0, 546.0), (2.0, 611.0))))


def _band_masses_of_weight(table, x, q):
    """Mass of the linear-between-nodes weight q(x) in each density's support, exactly."""
    grid = table.grid
    qg = np.interp(grid, x, q)
    return np.array([trapezoid(grid, np.where(p > 0, qg, 0.0)) for p in table.pdfs]) / trapezoid(grid, qg)


def test_uniform_is_four_equal_bands():
    t = stratified.uniform_table(380.0, 780.0)
    np.testing.assert_allclose(trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-14)
    # Band k samples [380 + 100 k, 380 + 100 (k + 1)]: F_k^-1(u) = 380 + 100 (k + u) up to the
    # 0.01 nm hand-over step.
    u = np.linspace(0.0, 1.0, 101)
    lam = np.asarray(sampling.sample_four(t.grid, t.pdfs, u))
    expected = 380.0 + 100.0 * (np.arange(4)[:, None] + u[None, :])
    np.testing.assert_allclose(lam, expected, atol=0.02)


@pytest.mark.parametrize("weight", stratified.WEIGHTS)
def test_densities_normalized_and_bands_of_equal_mass(weight):
    t = stratified.stratified_table(LINES, weight)
    assert np.all(t.pdfs >= 0)
    np.testing.assert_allclose(trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-13)
    x, q = stratified.weighted_spectrum(LINES, weight, 380.0, 780.0)
    # Each band holds a quarter of q, up to the 0.01 nm step where it hands over.
    np.testing.assert_allclose(_band_masses_of_weight(t, x, q), 0.25, atol=2e-3)


@pytest.mark.parametrize("weight", stratified.WEIGHTS)
def test_mixture_is_the_normalized_weight(weight):
    """The balance-heuristic density (1/4) sum_k p_k is q / mass(q): the table importance-
    samples q exactly, wherever q is linear between the nodes."""
    t = stratified.stratified_table(LINES, weight)
    x, q = stratified.weighted_spectrum(LINES, weight, 380.0, 780.0)
    lam = np.linspace(380.0, 780.0, 40_001)
    mix = np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam))
    target = np.interp(lam, x, q) / trapezoid(x, q)
    np.testing.assert_allclose(mix, target, rtol=2e-3, atol=1e-9 * target.max())


def test_weights_multiply_the_spectrum():
    x, q = stratified.weighted_spectrum(LINES, "spd", 380.0, 780.0)
    np.testing.assert_array_equal(q, LINES(x))
    from wavelength_pdf.colorimetry import cmfs

    wl, cmf = cmfs()
    x, q = stratified.weighted_spectrum(LINES, "luminance", 380.0, 780.0)
    assert set(wl[(wl >= 380) & (wl <= 780)]) <= set(x)
    np.testing.assert_allclose(q, LINES(x) * np.interp(x, wl, cmf[:, 1]), rtol=1e-15)


def test_unbiased_estimate_of_any_integrand():
    """Balance-heuristic estimates over u integrate f exactly (a stratified table's mixture is
    positive wherever the weight is): the mean of C(u) over a fine u grid equals the integral."""
    t = stratified.stratified_table(LINES, "spd")
    f = lambda lam: LINES(lam) * (1.0 + 0.5 * np.sin(lam / 23.0))  # noqa: E731
    u = (np.arange(200_000) + 0.5) / 200_000
    lam = np.asarray(sampling.sample_four(t.grid, t.pdfs, u))
    w = np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam)) * 4.0
    estimate = np.mean(np.sum(f(lam) / w, axis=0))
    x = np.linspace(380.0, 780.0, 2_000_001)
    np.testing.assert_allclose(estimate, trapezoid(x, f(x)), rtol=1e-4)


def test_a_line_narrower_than_the_step():
    """One 0.004 nm line holding all the power: cuts inside it, steps shrunk to fit, four
    non-empty bands, and no density outside the line."""
    s = _spectrum([380.0, 549.998, 550.0, 550.002, 780.0], [0.0, 0.0, 1.0, 0.0, 0.0])
    t = stratified.stratified_table(s, "spd")
    np.testing.assert_allclose(trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-12)
    assert np.all(np.diff(t.grid) > 0)
    for p in t.pdfs:
        support = t.grid[p > 0]
        assert support.min() >= 549.998 and support.max() <= 550.002


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.0, 1e3), min_size=3, max_size=40),
       st.lists(st.floats(0.01, 30.0), min_size=2, max_size=39))
def test_any_weight_gives_a_valid_table(values, gaps):
    n = min(len(values), len(gaps) + 1)
    q = np.asarray(values[:n])
    x = 380.0 + np.concatenate([[0.0], np.cumsum(gaps[: n - 1])])
    if trapezoid(x, q) <= 0:
        with pytest.raises(stratified.StratifiedError):
            stratified.equal_mass_table(x, q)
        return
    t = stratified.equal_mass_table(x, q)
    assert np.all(np.diff(t.grid) > 0) and t.grid[0] == x[0] and t.grid[-1] == x[-1]
    np.testing.assert_allclose(trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-12)
    # Wherever q > 0 at a node, the mixture is positive there (the table is unbiased).
    mix = t.pdfs.sum(axis=0)
    qg = np.interp(t.grid, x, q)
    qg[qg < 1e-300 * qg.max()] = 0.0  # design §3.3
    assert np.all(mix[qg > 0] > 0)


@pytest.mark.parametrize("x, q", [([380.0], [1.0]), ([380.0, 380.0], [1.0, 1.0]),
                                  ([380.0, 400.0], [0.0, 0.0]), ([380.0, 400.0], [1.0, -1.0]),
                                  ([380.0, 400.0], [1.0, np.nan]), ([380.0, np.inf], [1.0, 1.0])])
def test_bad_weights_are_refused(x, q):
    with pytest.raises(stratified.StratifiedError):
        stratified.equal_mass_table(x, q)


def test_visible_table_is_pbrt_visible_density():
    t = stratified.visible_table()
    assert (t.grid[0], t.grid[-1]) == (360.0, 830.0)
    lam = np.linspace(361.0, 829.0, 2000)
    mix = np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam))
    # pbrt-v4's normalization of sech^2(0.0072 (lambda - 538)) over 360..830 nm.
    norm = (np.tanh(0.0072 * (830 - 538)) - np.tanh(0.0072 * (360 - 538))) / 0.0072
    np.testing.assert_allclose(mix, stratified.visible_density(lam) / norm, rtol=1e-4)


def test_command_writes_readable_tables(tmp_path, capsys):
    assert main(["baseline", "uniform", "-o", str(tmp_path / "u.csv")]) == 0
    assert main(["baseline", "xyz", "cie:FL11", "-o", str(tmp_path / "x.csv")]) == 0
    assert main(["baseline", "start", "cie:FL11", "-o", str(tmp_path / "s.csv")]) == 0
    x = read_table(tmp_path / "x.csv")
    assert "method: xyz" in x.comments
    # The optimizer's start is the equal-mass partition on the optimizer's grid.
    from wavelength_pdf.optimize import starting_table
    from wavelength_pdf.spectra import load_spectrum

    s = read_table(tmp_path / "s.csv")
    ref = starting_table(load_spectrum("cie:FL11"))
    np.testing.assert_array_equal(s.grid, ref.grid)
    np.testing.assert_allclose(s.pdfs, ref.pdfs, rtol=1e-15)


@pytest.mark.parametrize("argv, message", [
    (["baseline", "spd", "-o", "x.csv"], "needs a SPECTRUM"),
    (["baseline", "uniform", "cie:A", "-o", "x.csv"], "takes no SPECTRUM"),
])
def test_command_refuses_bad_use(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists()
