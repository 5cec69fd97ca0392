"""The equal-mass initialization and the other starting points."""

import numpy as np
import pytest

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import colorimetry, init
from wavelength_pdf.problem import make_problem
from wavelength_pdf.spectra import Spectrum

GRID = np.arange(380.0, 781.0, 20.0)
_cmf_wl, _cmf = colorimetry.cmfs()


def _spectrum(name, wl, val):
    return Spectrum(name, f"test:{name}", np.asarray(wl, float), np.asarray(val, float))


SPECTRA = {
    "smooth": _spectrum("smooth", np.arange(370.0, 791.0, 5.0),
                        1.0 + 0.6 * np.sin(np.arange(370.0, 791.0, 5.0) / 37.0)),
    "lines": _spectrum("lines", np.arange(380.0, 781.0, 1.0),
                       0.02 + sum(np.exp(-0.5 * ((np.arange(380.0, 781.0, 1.0) - c) / 0.9) ** 2)
                                  for c in (436, 546, 611))),
    "line": _spectrum("line", [432.0, 433.0, 434.0], [0.0, 1.0, 0.0]),
    "gaps": _spectrum("gaps", [380.0, 450.0, 450.5, 649.5, 650.0, 780.0], [1.0, 2.0, 0.0, 0.0, 1.5, 0.5]),
}


@pytest.fixture(scope="module", params=list(SPECTRA))
def case(request):
    s = SPECTRA[request.param]
    return s, make_problem(s, GRID)


def _q(lam, s):
    return np.interp(lam, s.wavelengths, s.values, left=0.0, right=0.0) * sum(
        np.interp(lam, _cmf_wl, _cmf[:, i], left=0.0, right=0.0) for i in range(3))


def _fine(a, b):
    x = np.unique(np.concatenate([np.linspace(a, b, 400_001), _cmf_wl[(_cmf_wl > a) & (_cmf_wl < b)]]))
    return x, 0.5 * (x[1:] + x[:-1])


def test_densities_are_normalized_non_negative(case):
    _, p = case
    P = init.equal_mass_partition(p)
    assert P.shape == (4, GRID.size)
    assert np.all(P >= 0)
    np.testing.assert_allclose(np.trapezoid(P, GRID, axis=1), 1.0, rtol=1e-13)


def test_cuts_split_q_into_four_equal_masses(case):
    s, p = case
    cuts = init.equal_mass_cuts(p)
    assert cuts[0] == GRID[0] and cuts[-1] == GRID[-1] and np.all(np.diff(cuts) >= 0)
    masses = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        x, mid = _fine(a, b)
        masses.append(np.sum(_q(mid, s) * np.diff(x)))
    masses = np.array(masses)
    np.testing.assert_allclose(masses / masses.sum(), 0.25, rtol=1e-6)


def test_each_density_covers_its_part_and_the_parts_add_up(case):
    s, p = case
    cuts = init.equal_mass_cuts(p)
    H = init.hat_parts(p, cuts)
    # The trapezoid rule of each part's hat averages is exactly the part's mass.
    for k, (a, b) in enumerate(zip(cuts[:-1], cuts[1:])):
        x, mid = _fine(a, b)
        want = np.sum(_q(mid, s) * np.diff(x)) * p.scale
        assert np.trapezoid(H[k], GRID) == pytest.approx(want, rel=1e-6)
        # Density k lives on the nodes whose hat functions meet [a_k, a_k+1].
        outside = (GRID < a - 20.0) | (GRID > b + 20.0)
        assert np.all(H[k, outside] == 0.0)


def test_mixture_is_positive_at_both_ends_of_every_segment_where_f_is_positive(case):
    s, p = case
    m = init.equal_mass_partition(p).sum(axis=0)
    for i in range(GRID.size - 1):
        x = np.linspace(GRID[i], GRID[i + 1], 2001)[1:-1]
        if np.any(_q(x, s) > 0):
            assert m[i] > 0 and m[i + 1] > 0, f"segment {GRID[i]}-{GRID[i + 1]} nm"
    np.testing.assert_array_equal(init.support_nodes(p), m > 0)


def test_a_line_between_two_nodes_gets_its_mass_on_those_nodes():
    p = make_problem(SPECTRA["line"], GRID)
    P = init.equal_mass_partition(p)
    around = (GRID == 420.0) | (GRID == 440.0)
    assert np.all(P[:, around] > 0) and np.all(P[:, ~around] == 0.0)
    # The line's mass sits nearer 440 than 420 (432-434 nm): so does every density.
    assert np.all(P[:, GRID == 440.0] > P[:, GRID == 420.0])


def test_starting_points_are_deterministic_and_respect_the_support():
    p = make_problem(SPECTRA["gaps"], GRID)
    a = init.starting_points(p, seed=0)
    b = init.starting_points(p, seed=0)
    c = init.starting_points(p, seed=1)
    assert list(a) == list(b) and list(a)[0] == "equal-mass"
    for name in a:
        np.testing.assert_array_equal(a[name], b[name])
        np.testing.assert_allclose(np.trapezoid(a[name], GRID, axis=1), 1.0, rtol=1e-12)
        assert np.all(a[name][:, ~init.support_nodes(p)] == 0.0), name
    assert not np.array_equal(a["random0"], c["random0"])
    # On a coarser grid of the same range too.
    coarse = GRID[::2]
    for name, V in init.starting_points(p, seed=0, grid=coarse).items():
        assert V.shape == (4, coarse.size)
        np.testing.assert_allclose(np.trapezoid(V, coarse, axis=1), 1.0, rtol=1e-12)
