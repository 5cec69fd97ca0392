"""Solvers lower J, keep the estimator healthy, and are reproducible; the public entry
point returns a complete, accepted result. Small budgets on a small problem."""

import numpy as np
import pytest

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import health, init, objective, solvers
from wavelength_pdf.budget import Budget
from wavelength_pdf.optimize import Result, evaluate_table, optimize_spectrum
from wavelength_pdf.problem import make_problem
from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.table import Table

GRID = np.arange(380.0, 781.0, 20.0)  # the same compiled shape as test_objective


def _lamp():
    """A continuum with two broad bands (a phosphor-like lamp), sampled every 2 nm."""
    wl = np.arange(380.0, 781.0, 2.0)
    val = 0.3 + 0.2 * np.sin(wl / 50.0) + sum(a * np.exp(-0.5 * ((wl - c) / 15.0) ** 2)
                                              for c, a in [(450, 1.0), (600, 1.5)])
    return Spectrum("lamp", "test:lamp", wl, val)


@pytest.fixture(scope="module")
def problem():
    return make_problem(_lamp(), GRID)


def test_registry():
    assert set(solvers.SOLVERS) == {"multistage", "lbfgsb", "trust-constr", "ipopt"}
    assert solvers.DEFAULT_SOLVER == "multistage"
    assert all(entry.name == name for name, entry in solvers.SOLVERS.items())
    assert solvers.SOLVERS["ipopt"].requires == "cyipopt"


@pytest.mark.parametrize("name,budget", [("lbfgsb", 60), ("trust-constr", 40), ("ipopt", 40), ("multistage", 200)])
def test_each_solver_lowers_J_and_stays_healthy(problem, name, budget):
    P0 = init.equal_mass_partition(problem)
    J0 = objective.J(problem, P0)
    steps = []
    r = solvers.SOLVERS[name](solvers.Start.of(problem, P0), Budget(budget), seed=0,
                              progress=lambda k, J: steps.append((k, J)))
    assert r.J < 0.8 * J0, f"{name}: J {r.J} vs initialization {J0}"
    np.testing.assert_allclose(np.trapezoid(r.P, GRID, axis=1), 1.0, rtol=1e-12)
    assert np.all(r.P >= 0)
    h0 = health.health(problem, P0)
    h = health.health(problem, r.P)
    assert h.accepted(h0), h.reason(h0)
    # The mixture never vanishes where the lamp shines (the defensive share).
    assert np.all(r.P.sum(axis=0)[init.support_nodes(problem)] > 0)
    # Progress: one call per evaluation, best J so far never rises.
    assert [k for k, _ in steps] == list(range(1, len(steps) + 1)) and len(steps) == r.nfev <= budget
    Js = [J for _, J in steps]
    assert all(b <= a for a, b in zip(Js, Js[1:]))


def test_same_input_and_seed_give_the_same_table(problem):
    P0 = init.equal_mass_partition(problem)
    start = solvers.Start.of(problem, P0)
    a = solvers.multistage(start, Budget(120), seed=3)
    b = solvers.multistage(start, Budget(120), seed=3)
    np.testing.assert_array_equal(a.P, b.P)
    assert a.J == b.J and a.history == b.history


def test_levels_interpolate_exactly():
    support = np.ones(GRID.size, dtype=bool)
    for stride in (1, 2, 4, 7):
        lev = solvers.make_level(GRID, support, stride)
        assert lev.grid[0] == GRID[0] and lev.grid[-1] == GRID[-1]
        v = np.random.default_rng(stride).random(lev.grid.size)
        np.testing.assert_allclose(lev.E @ v, np.interp(GRID, lev.grid, v), rtol=1e-14)


def test_optimize_spectrum_returns_an_accepted_result():
    r = optimize_spectrum(_lamp(), grid=GRID, seed=0, solver_options={"max_evals": 200})
    assert isinstance(r, Result) and r.accepted, r.message
    assert r.J < r.J_init and r.J < r.J_uniform
    assert abs(r.J - r.J_fine) < 1e-3 * r.J
    assert isinstance(r.table, Table) and r.table.pdfs.shape == (4, GRID.size)
    np.testing.assert_array_equal(r.table.grid, GRID)
    text = "\n".join(r.to_table().comments)
    for key in ("J_uniform", "J_init", "J_fine", "bias_rel", "std_rel", "solver: multistage", "test:lamp"):
        assert key in text
    assert r.health.accepted(r.health_init) and len(r.history) > 0 and r.seconds > 0
    # Scoring the written table gives the same numbers.
    ev = evaluate_table(_lamp(), r.table)
    assert isinstance(ev, Result) and ev.accepted
    assert ev.J == pytest.approx(r.J, rel=1e-12)
    assert ev.J_uniform == pytest.approx(r.J_uniform, rel=1e-12)


def test_a_second_search_keeps_only_a_better_accepted_table(monkeypatch):
    """A result above the threshold is searched again (more starts kept, more evaluations);
    the second table replaces the first only if its J is lower and it is accepted."""
    options = {"max_evals": 60}
    monkeypatch.setattr(solvers, "SECOND_SEARCH_ABOVE", np.inf)  # never
    first = optimize_spectrum(_lamp(), grid=GRID, solver_options=options)
    monkeypatch.setattr(solvers, "SECOND_SEARCH_ABOVE", 0.0)  # always
    both = optimize_spectrum(_lamp(), grid=GRID, solver_options=options)
    assert both.accepted and both.J <= first.J
    if "second search" in both.message:
        assert both.J < first.J and len(both.history) > len(first.history)
    else:  # the second search found nothing better: the first table stands
        np.testing.assert_array_equal(both.table.pdfs, first.table.pdfs)
    again = optimize_spectrum(_lamp(), grid=GRID, solver_options=options)
    np.testing.assert_array_equal(again.table.pdfs, both.table.pdfs)


def test_optimize_spectrum_rejects_unknown_solver_and_grid():
    with pytest.raises(ValueError, match="unknown solver"):
        optimize_spectrum(_lamp(), solver="gurobi")
    with pytest.raises(ValueError, match="auto"):
        optimize_spectrum(_lamp(), grid="fine")
