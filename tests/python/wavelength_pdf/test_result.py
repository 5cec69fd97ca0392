"""The one result record: its header round trip, and the one acceptance rule."""
from __future__ import annotations

import numpy as np
import pytest

from wavelength_pdf import health as health_mod, init
from wavelength_pdf.optimize import evaluate_table
from wavelength_pdf.problem import make_problem
from wavelength_pdf.result import SUMMARY_FIELDS, Result, read_header
from wavelength_pdf.spectra import load_spectrum
from wavelength_pdf.table import Table, read_table, write_table

GRID = np.linspace(380.0, 780.0, 41)


@pytest.fixture(scope="module")
def fl2():
    sp = load_spectrum("cie:FL2")
    problem = make_problem(sp, GRID)
    return sp, problem, init.equal_mass_partition(problem)


def test_header_round_trip(tmp_path, fl2):
    """A record written as a table's header reads back field for field, bit for bit."""
    sp, _, P0 = fl2
    r = evaluate_table(sp, Table(GRID, P0))
    r.solver, r.seed, r.message, r.seconds = "multistage", 7, "a message\nover two lines", 1.25
    write_table(tmp_path / "t.csv", r.to_table())
    back = Result.from_table(read_table(tmp_path / "t.csv"))
    for name in ("J", "J_fine", "J_uniform", "J_init", "bias_rel", "reason", "name", "source",
                 "solver", "seed", "seconds", "accepted"):
        assert getattr(back, name) == getattr(r, name), name
    np.testing.assert_array_equal(back.std_rel, r.std_rel)
    np.testing.assert_array_equal(back.init_std_rel, r.init_std_rel)
    assert back.message == "a message over two lines"
    np.testing.assert_array_equal(back.table.pdfs, r.table.pdfs)
    # The summary row is the same from the record and from its header.
    assert back.summary_row("in", "t.csv", "kept") == r.summary_row("in", "t.csv", "kept")
    assert list(r.summary_row("in", "t.csv", "written")) == SUMMARY_FIELDS


def test_header_of_a_foreign_table_gives_nan_not_an_error(tmp_path):
    t = Table(GRID, np.ones((4, GRID.size)) / 400.0, ["made elsewhere", "J: 1.5"])
    r = Result.from_table(t)
    assert r.J == 1.5 and np.isnan(r.J_uniform) and np.all(np.isnan(r.std_rel))
    assert read_header(t) == {"J": "1.5"}


def test_rule_rejects_a_table_worse_than_uniform(fl2):
    """Unbiased, no channel worse than the initialization, but J above uniform's: rejected,
    by the record and by the rule itself."""
    _, problem, P0 = fl2
    h = health_mod.health(problem, P0)
    assert health_mod.rejection(h, h) == ""
    reason = health_mod.rejection(h, h, J=2.0, J_uniform=1.0)
    assert "worse than stratified uniform" in reason
    r = Result.judge(Table(GRID, P0), J=2.0, J_fine=2.0, J_uniform=1.0, J_init=2.0, health=h,
                     health_init=h)
    assert not r.accepted and r.reason == reason
    assert "accepted: False" in r.header_lines()
    assert health_mod.rejection(h, h, J=1.0, J_uniform=1.0) == "", "equal to uniform is fine"
    assert "J is not a number" in health_mod.rejection(h, h, J=float("nan"), J_uniform=1.0)


def test_rule_rejects_bias_and_worse_std(fl2):
    sp, problem, P0 = fl2
    biased = np.where(GRID[None, :] < 500.0, 0.0, P0 + 1e-3)
    r = evaluate_table(sp, Table(GRID, biased))
    assert not r.accepted and "relative bias" in r.reason
    h0 = health_mod.health(problem, P0)
    worse = health_mod.Health(bias=0.0, bias_xyz=np.zeros(3), std=h0.std * [1.0, 1.1, 1.0],
                              missing_mass=np.zeros(3))
    assert "channel(s) Y" in health_mod.rejection(worse, h0)
    assert worse.accepted() and not worse.accepted(h0)


def test_evaluate_table_of_uniform_like_table_is_judged_against_uniform(fl2):
    """A flat table on a line lamp: J far above uniform's cannot be accepted."""
    sp = load_spectrum("cie:FL11")
    flat = np.ones((4, GRID.size))
    flat[1:, :] = np.linspace(0.2, 1.8, GRID.size)  # different shapes, all positive
    r = evaluate_table(sp, Table(GRID, flat))
    assert r.accepted == (r.J <= r.J_uniform and r.reason == "")
