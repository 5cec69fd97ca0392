"""Inputs that would exhaust memory or time, or defeat double precision (design §2.3, §3.3, §4.4, §7).

- A table grid finer than the optimizer can hold is refused before any work, with the node
  count, the memory it would need and the limit.
- ``--max-seconds`` is a cap on the whole call: when it is spent compiling, the search does
  not start; a capped result is never accepted when it is worse than stratified uniform.
- Spectra of extreme magnitude are scaled exactly; values below 1e-300 of the peak (which
  double precision cannot hold next to it) are read as 0, so a Gaussian line whose tails
  reach the subnormal numbers is read, and a comb of 1e300 and 1e-300 becomes spikes.
"""
from __future__ import annotations

import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf import cli
from wavelength_pdf.model import DEFAULT_GRID, MAX_TABLE_NODES, TooLargeError, optimizer_memory
from wavelength_pdf.spectra import (MAX_DYNAMIC_RANGE, PEAK_RANGE, load_spectrum,
                                    make_spectrum, read_spd)
from wavelength_pdf.table import Table, read_table, write_table

from repo_paths import REPO  # noqa: E402


# --- node counts ------------------------------------------------------------------------

def test_absurdly_fine_grid_step_is_refused_before_any_work(tmp_path, capsys):
    t = time.monotonic()
    code = cli.main(["optimize", "cie:D65", "--grid-step", "0.01", "-o", str(tmp_path / "t.csv")])
    seconds = time.monotonic() - t
    err = capsys.readouterr().err
    assert code == 2, err
    assert "40001 nodes" in err and f"limit is {MAX_TABLE_NODES} nodes" in err
    gb = float(re.search(r"about ([0-9.e+]+) GB", err).group(1))
    assert gb == pytest.approx(optimizer_memory(40001) / 1e9, rel=1e-2) and gb > 10
    assert not (tmp_path / "t.csv").exists()
    assert seconds < 30, "refused before the optimization, not after"


def test_a_step_that_would_not_fit_in_any_memory_is_refused_without_allocating(tmp_path, capsys):
    # 4e11 nodes: building the grid alone would take 3 TB.
    assert cli.main(["optimize", "cie:D65", "--grid-step", "1e-9", "-o", str(tmp_path / "t.csv")]) == 2
    assert "400000000001 nodes" in capsys.readouterr().err


def test_the_limit_itself_is_accepted_and_the_library_refuses_beyond_it():
    from wavelength_pdf.problem import make_problem
    from wavelength_pdf.produce import make_grid

    assert make_grid(380.0, 780.0, "0.1").size == MAX_TABLE_NODES
    with pytest.raises(TooLargeError, match=f"{MAX_TABLE_NODES + 1} nodes"):
        make_problem(load_spectrum("cie:D65"), np.linspace(380.0, 780.0, MAX_TABLE_NODES + 1))


def test_a_spectrum_needing_more_memory_than_the_machine_has_is_refused(monkeypatch):
    from wavelength_pdf import model
    from wavelength_pdf.problem import make_problem

    n = 30000
    rng = np.random.default_rng(1)
    wl = np.linspace(380.0, 780.0, n)
    # Noise does not thin away (problem.SPECTRUM_TOL): every sample is a node, and they
    # need ~0.9 GB beyond the optimizer's own 0.7 GB. A machine of 1 GB refuses them...
    sp = make_spectrum("noise", "noise.spd", wl, 1.0 + rng.random(n))
    monkeypatch.setattr(model, "physical_memory", lambda: 1e9)
    with pytest.raises(TooLargeError, match=r"noise\.spd: .* 30\d\d\d distinct nodes .* GB of memory, "
                                            r"more than this machine's 1 GB"):
        make_problem(sp, DEFAULT_GRID)
    # ... one of 4 GB takes them.
    monkeypatch.setattr(model, "physical_memory", lambda: 4e9)
    assert make_problem(sp, DEFAULT_GRID).n_nodes > n


def test_any_table_the_optimizer_may_write_is_readable_by_the_renderers_limit(tmp_path):
    """The node limit keeps every table far below the readers' 64 MiB (design §2.3)."""
    grid = np.linspace(380.0, 780.0, MAX_TABLE_NODES)
    rng = np.random.default_rng(0)
    pdfs = rng.random((4, grid.size)) * (1.0 / 3.0)  # full-precision digits in every cell
    path = tmp_path / "largest.csv"
    write_table(path, Table(grid=grid, pdfs=pdfs, comments=["x" * 200] * 20))
    assert path.stat().st_size < 64 * 2**20 / 16
    assert read_table(path).grid.size == MAX_TABLE_NODES


# --- the time cap -------------------------------------------------------------------------

def _comb_spd(path: Path, high: float = 1.0, low: float = 0.0) -> Path:
    """A spectrum alternating between two values every nanometre."""
    path.write_text("".join(f"{w} {high if i % 2 == 0 else low!r}\n"
                            for i, w in enumerate(range(380, 781))))
    return path


def test_a_capped_result_worse_than_uniform_is_not_accepted(tmp_path):
    """At a cap spent before the search starts the result is the initialization; on a comb
    of 1 nm lines the initialization is worse than stratified uniform sampling, so it must
    not be accepted (design §4.4), and optimize does not write it."""
    from wavelength_pdf.optimize import optimize_spectrum

    sp = read_spd(_comb_spd(tmp_path / "comb.spd"))
    r = optimize_spectrum(sp, grid=DEFAULT_GRID, max_seconds=1e-3)
    assert r.J > r.J_uniform, "the test needs an initialization worse than uniform"
    assert not r.accepted and "worse than stratified uniform" in r.reason
    assert "time cap" in r.message and r.history == []
    out = tmp_path / "t.csv"
    assert cli.main(["optimize", str(tmp_path / "comb.spd"), "--grid-step", "5",
                     "--max-seconds", "0.001", "-q", "-o", str(out)]) == cli.EXIT_NOT_ACCEPTED
    assert not out.exists()


def test_max_seconds_must_be_finite_and_positive_in_the_library_too():
    from wavelength_pdf.optimize import optimize_spectrum

    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="max_seconds"):
            optimize_spectrum(load_spectrum("cie:D65"), max_seconds=bad)


def _timed(argv: list[str], env: dict) -> tuple[float, subprocess.CompletedProcess]:
    t = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "wavelength_pdf", *argv], capture_output=True,
                       text=True, env=env, timeout=600)
    return time.monotonic() - t, r


@pytest.mark.slow
def test_max_seconds_caps_the_wall_time_including_compilation(tmp_path):
    """``optimize --max-seconds 2`` takes at most a few seconds more than scoring a table.

    The start-up is measured in the same run: ``show TABLE --spectrum`` reads the spectrum
    and computes exactly the figures every result reports (J of the table, of the
    initialization and of stratified uniform sampling, the health), which no cap can skip.
    The two share a compilation cache that starts empty: ``show`` compiles those figures,
    ``optimize`` finds them there but has never compiled its search. Before the cap counted
    compiling, the optimizer compiled and ran its search whatever was left of the cap:
    13-39 s for a 2 s cap (here: 20 s more than ``show`` on a loaded machine).
    """
    table = tmp_path / "uniform.csv"
    write_table(table, Table(grid=DEFAULT_GRID, pdfs=np.ones((4, DEFAULT_GRID.size))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO / "python"), os.environ.get("PYTHONPATH", "")]))
    env["WAVELENGTH_PDF_JAX_CACHE"] = str(tmp_path / "cache")
    startup, r = _timed(["show", str(table), "--spectrum", "cie:FL11"], env)
    assert r.returncode == 0, r.stderr
    wall, r = _timed(["optimize", "cie:FL11", "--max-seconds", "2", "-q", "-o",
                      str(tmp_path / "t.csv")], env)
    assert r.returncode in (0, 1), r.stderr
    print(f"show (start-up and figures): {startup:.1f} s; optimize --max-seconds 2: {wall:.1f} s")
    assert wall < startup + 2.0 + 6.0, (f"optimize --max-seconds 2 took {wall:.1f} s; scoring "
                                        f"a table took {startup:.1f} s\n{r.stdout}")


def _slow(fn, seconds):
    def slow(*a, **k):
        time.sleep(seconds)
        return fn(*a, **k)
    return slow


def test_the_search_does_not_start_when_the_figures_spent_the_cap(monkeypatch):
    """A cap smaller than what the reference figures take (here made slow: they stand for
    a compilation) leaves no search, and the call ends soon after the cap."""
    from wavelength_pdf import uniform
    from wavelength_pdf.optimize import optimize_spectrum

    sp = load_spectrum("cie:D65")
    optimize_spectrum(sp, grid=DEFAULT_GRID, solver_options={"max_evals": 1})  # compiled
    monkeypatch.setattr(uniform, "uniform_J", _slow(uniform.uniform_J, 1.0))
    t = time.monotonic()
    r = optimize_spectrum(sp, grid=DEFAULT_GRID, max_seconds=1.5)
    assert r.history == [] and "not started" in r.message
    assert time.monotonic() - t < 1.5 + 1.0


def test_the_solvers_clock_includes_its_own_compiling(monkeypatch):
    """The solver's deadline starts when it is called, before it prepares (compiles) its
    objective: a cap spent preparing leaves no evaluation."""
    from wavelength_pdf import init, solvers
    from wavelength_pdf import problem as problem_mod
    from wavelength_pdf.budget import Budget
    from wavelength_pdf.problem import make_problem

    problem = make_problem(load_spectrum("cie:D65"), DEFAULT_GRID)
    start = solvers.Start.of(problem, init.equal_mass_partition(problem))
    monkeypatch.setattr(problem_mod, "simplify", _slow(problem_mod.simplify, 1.0))
    run = solvers.SOLVERS["multistage"](start, Budget.starting(1000, 0.5))
    assert run.nfev == 0 and run.history == []
    assert "time cap" in run.message


# --- extreme values -------------------------------------------------------------------------

def test_values_below_1e300th_of_the_peak_are_read_as_zero(tmp_path):
    """A comb alternating 1e300 and 1e-300 is read as spikes of 1e300 on zeros, scaled to a
    peak in [0.5, 1): every value kept is a normal double, and the spikes keep their ratios."""
    spd = _comb_spd(tmp_path / "alt.spd", high=1e300, low=1e-300)
    sp = load_spectrum(str(spd))
    raw = np.loadtxt(spd)[:, 1]
    assert np.all(sp.values[raw < 1] == 0.0)
    kept = sp.values[raw > 1]
    assert np.all(kept >= 0.5) and np.all(kept < 1.0) and np.all(kept == kept[0])


def test_a_gaussian_line_whose_tails_reach_the_subnormals_is_read():
    """A 0.1 nm line on a 0.01 nm list: its tails fall to 5e-324 and to 0; the tails below
    1e-300 of the peak are read as 0, the line itself bit for bit."""
    wl = np.round(np.arange(360.0, 830.0 + 1e-9, 0.01), 6)
    sigma = 0.1 / (2.0 * math.sqrt(2.0 * math.log(2.0)))
    raw = np.exp(-0.5 * ((wl - 532.0) / sigma) ** 2)
    assert raw[raw > 0].min() < 1e-307  # the case: subnormal tails
    sp = make_spectrum("line", "test", wl, raw)
    big = raw >= 1e-300
    np.testing.assert_array_equal(sp.values[big], raw[big])
    assert np.all(sp.values[~big] == 0.0)


@pytest.mark.parametrize("scale", [1.7e308 / 117.812, 1e300, 1e-300, 2.0**-1000, 1e-310])
def test_spectra_of_any_magnitude_are_scaled_exactly(scale):
    d65 = load_spectrum("cie:D65")
    raw = np.asarray(d65.values) * scale
    sp = make_spectrum("scaled", "test", d65.wavelengths, raw)
    peak = float(sp.values.max())
    assert PEAK_RANGE[0] <= peak <= PEAK_RANGE[1] and np.all(np.isfinite(sp.values))
    # A power of two: every ratio is kept bit for bit.
    k = math.log2(peak / float(raw.max()))
    assert k == round(k)
    np.testing.assert_array_equal(sp.values, np.ldexp(raw, int(round(k))))


def test_ordinary_spectra_keep_their_values():
    raw = [0.0, 3.5, 1e6, 2.0]
    np.testing.assert_array_equal(make_spectrum("x", "t", [400, 500, 600, 700], raw).values, raw)


def test_huge_spectrum_gives_the_same_problem_and_a_scene_the_renderer_can_read():
    """The objective does not see the scale; the evaluation's scene (single precision in the
    renderer) gets values it can hold."""
    from wavelength_pdf.evaluation.scene_edit import inline_spectrum
    from wavelength_pdf.problem import make_problem

    d65 = load_spectrum("cie:D65")
    huge = make_spectrum("huge", "test", d65.wavelengths, np.asarray(d65.values) * 1e300)
    a, b = make_problem(d65, DEFAULT_GRID), make_problem(huge, DEFAULT_GRID)
    np.testing.assert_allclose(b.spec, a.spec, rtol=1e-14)
    np.testing.assert_allclose(b.c, a.c, rtol=1e-14)
    numbers = [float(v) for v in inline_spectrum(huge, 380, 780).strip("[] ").split()]
    assert max(numbers) < 3.4e38 and min(v for v in numbers if v > 0) > 1.2e-38


def test_negligible_value_limit_is_the_documented_one():
    kept = make_spectrum("ok", "t", [400, 500], [1.0, 1.0 / MAX_DYNAMIC_RANGE * 10])
    assert kept.values[1] > 0
    dropped = make_spectrum("tiny", "t", [400, 500], [1.0, 1.0 / MAX_DYNAMIC_RANGE / 10])
    assert dropped.values[1] == 0.0 and dropped.values[0] == 1.0


def test_a_scene_written_from_a_line_carries_no_value_that_single_precision_loses():
    from wavelength_pdf.evaluation.scene_edit import SCENE_FLOOR, inline_spectrum

    sp = make_spectrum("line", "t", [500, 530, 531, 532, 560], [1e-200, 1e-35, 1.0, 1e-20, 0.0])
    numbers = [float(v) for v in inline_spectrum(sp, 380, 780).strip("[] ").split()][1::2]
    assert max(numbers) == 1.0 and min(v for v in numbers if v > 0) >= SCENE_FLOOR
    assert numbers.count(1e-20) == 1  # above the floor: kept
