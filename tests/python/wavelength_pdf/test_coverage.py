"""Coverage (design §1.5): where a table never samples light that the spectrum emits.

Analytic cases: the fractions are integrals of the spectrum times the CMFs over known
intervals, computed here independently (on a fine grid, by NumPy's trapezoid rule) and
compared with the module's exact piecewise integration.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

from wavelength_pdf import cli
from wavelength_pdf.colorimetry import cmfs
from wavelength_pdf.coverage import (OUTSIDE_LUMINANCE_FRACTION, coverage,
                                     zero_mixture_intervals)
from wavelength_pdf.spectra import make_spectrum
from wavelength_pdf.table import Table, write_table

GRID = np.arange(380.0, 781.0, 5.0)


def _flat(lo: float, hi: float):
    return make_spectrum("flat", "test", [lo, hi], [1.0, 1.0])


def _ybar_integral(a: float, b: float, spectrum=None) -> float:
    """Integral of spectrum * ybar over [a, b] (fine trapezoid rule, independent check)."""
    wl, val = cmfs()
    x = np.linspace(a, b, 200001)
    s = np.ones_like(x) if spectrum is None else spectrum(x)
    return float(np.trapezoid(s * np.interp(x, wl, val[:, 1], left=0, right=0), x))


def _table(grid, zero_between=None) -> np.ndarray:
    P = np.ones((4, grid.size))
    if zero_between is not None:
        a, b = zero_between
        P[:, (grid >= a) & (grid <= b)] = 0.0
    return P


def test_zero_mixture_intervals_are_runs_of_zero_segments():
    P = _table(GRID, (500, 600))
    assert zero_mixture_intervals(GRID, P) == [(500.0, 600.0)]
    # One density positive at 550 nm: two gaps, meeting at neither side of 550.
    P[2, GRID == 550] = 1.0
    assert zero_mixture_intervals(GRID, P) == [(500.0, 545.0), (555.0, 600.0)]
    # A single zero node is no gap (the mixture is linear and positive on both sides of it).
    P = _table(GRID)
    P[:, GRID == 600] = 0.0
    assert zero_mixture_intervals(GRID, P) == []


def test_gap_where_the_spectrum_emits_is_reported_with_its_luminance_share():
    sp = _flat(380, 780)
    cov = coverage(GRID, _table(GRID, (500, 600)), sp)
    assert cov.gaps == [(500.0, 600.0)]
    want = _ybar_integral(500, 600) / _ybar_integral(380, 780)
    assert cov.gap_luminance_fraction == pytest.approx(want, rel=1e-6)
    assert cov.outside == [] and not cov.outside_matters
    (w,) = cov.warnings("flat")
    assert "[500, 600] nm" in w and "--wavelength-pdf-defensive 0.01" in w


def test_gap_where_the_spectrum_is_dark_is_not_reported():
    sp = make_spectrum("two bands", "test", [380, 480, 480.001, 620, 620.001, 780],
                       [1, 1, 0, 0, 1, 1])
    cov = coverage(GRID, _table(GRID, (500, 600)), sp)
    assert cov.gaps == [] and cov.warnings() == []


def test_table_narrower_than_the_spectrum():
    sp = _flat(380, 780)
    grid = np.arange(450.0, 651.0, 5.0)
    cov = coverage(grid, _table(grid), sp)
    assert cov.gaps == []
    assert cov.outside == [(380.0, 450.0), (650.0, 780.0)]
    want = (_ybar_integral(380, 450) + _ybar_integral(650, 780)) / _ybar_integral(380, 780)
    assert cov.outside_luminance_fraction == pytest.approx(want, rel=1e-6)
    assert cov.outside_matters
    (w,) = cov.warnings("flat")
    assert "[380, 450] and [650, 780] nm" in w and "[450, 650] nm" in w and "--range" in w


def test_covering_table_gives_no_warning():
    cov = coverage(GRID, _table(GRID), _flat(400, 700))
    assert (cov.gaps, cov.outside) == ([], [])
    assert cov.gap_luminance_fraction == 0 and cov.outside_luminance_fraction == 0
    assert cov.warnings() == []


def test_tiny_emission_outside_the_range_is_below_the_threshold():
    # A flat lamp over the CMFs' whole range on the default 380..780 nm table: what lies
    # outside (the CMFs' far ends) is a few 1e-5 of the luminance, as the renderer finds.
    cov = coverage(GRID, _table(GRID), _flat(360, 830))
    want = (_ybar_integral(360, 380) + _ybar_integral(780, 830)) / _ybar_integral(360, 830)
    assert cov.outside_luminance_fraction == pytest.approx(want, rel=1e-6)
    assert want < OUTSIDE_LUMINANCE_FRACTION
    assert cov.outside == [(360.0, 380.0), (780.0, 830.0)]
    assert cov.outside_tristimulus_fraction < 1e-3 and cov.warnings() == []


def test_huge_values_do_not_overflow():
    sp = make_spectrum("huge", "test", [380, 780], [1.7e308, 1.7e308])
    cov = coverage(GRID, _table(GRID, (500, 600)), sp)
    want = _ybar_integral(500, 600) / _ybar_integral(380, 780)
    assert cov.gap_luminance_fraction == pytest.approx(want, rel=1e-6)


def _write_spd(path, lo, hi):
    path.write_text("".join(f"{w:g} 1\n" for w in np.arange(lo, hi + 0.5, 1.0)))
    return str(path)


def test_show_warns_about_a_gap_and_names_the_fix(tmp_path, capsys):
    table = tmp_path / "gap.csv"
    write_table(table, Table(grid=GRID, pdfs=_table(GRID, (500, 600))))
    spd = _write_spd(tmp_path / "flat.spd", 380, 780)
    assert cli.main(["show", str(table), "--spectrum", spd]) == 0
    err = capsys.readouterr().err
    assert "warning" in err and "[500, 600] nm" in err and "--wavelength-pdf-defensive" in err


def test_show_warns_about_a_table_that_misses_the_lamp(tmp_path, capsys):
    grid = np.arange(450.0, 651.0, 5.0)
    table = tmp_path / "narrow.csv"
    write_table(table, Table(grid=grid, pdfs=_table(grid)))
    spd = _write_spd(tmp_path / "flat.spd", 380, 780)
    assert cli.main(["show", str(table), "--spectrum", spd]) == 0
    err = capsys.readouterr().err
    assert "outside the table's range [450, 650] nm" in err


def test_show_is_silent_for_a_covering_table(tmp_path, capsys):
    table = tmp_path / "full.csv"
    write_table(table, Table(grid=GRID, pdfs=_table(GRID)))
    spd = _write_spd(tmp_path / "flat.spd", 400, 700)
    assert cli.main(["show", str(table), "--spectrum", spd]) == 0
    assert "warning" not in capsys.readouterr().err


# --- light at or beyond the table's ends: refused by optimize (design §3.3) -----------------

def _write_points(path, points) -> str:
    path.write_text("".join(f"{l!r} {v!r}\n" for l, v in points))
    return str(path)


def _gaussian(centre: float, sigma: float = 10.0):
    return [(centre + d / 10.0, float(np.exp(-0.5 * (d / 10.0 / sigma) ** 2))) for d in range(-1000, 1001)]


@pytest.mark.parametrize("centre, where, suggestion", [
    (780.0, "on [780, 830] nm", "--range 380 830 --grid-step 5"),
    (380.0, "on [360, 380] nm", "--range 360 780 --grid-step 5"),
])
def test_optimize_refuses_a_lamp_peaked_at_the_table_end(tmp_path, capsys, centre, where, suggestion):
    """optimize accepted such a lamp silently, while show then reported that renders miss
    a third of its luminance: now it is refused before any work, with the fix."""
    spd = _write_points(tmp_path / "peak.spd", _gaussian(centre))
    out = tmp_path / "t.csv"
    assert cli.main(["optimize", spd, "-o", str(out), "--max-evals", "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "outside the table's range [380, 780] nm" in err and where in err, err
    assert suggestion in err and "of its luminance" in err, err
    assert not out.exists()


def test_optimize_refuses_a_narrow_line_at_the_end_without_a_nan(tmp_path, capsys):
    """A 0.01 nm line at exactly 780 nm was refused as 'relative bias nan' (its Z is 0)."""
    spd = _write_points(tmp_path / "line.spd", [(779.99, 0.0), (780.0, 1.0), (780.01, 0.0)])
    out = tmp_path / "t.csv"
    assert cli.main(["optimize", spd, "-o", str(out), "--max-evals", "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "emits 50% of its luminance" in err and "on [780, 780.01] nm" in err, err
    assert "--range 380 785" in err, err
    assert not re.search(r"\bnan\b", err, re.IGNORECASE), err
    assert not out.exists()


def test_light_outside_below_the_refusal_is_a_warning():
    """Between the reporting thresholds of design §1.5 and 1 %: the warning show prints."""
    from wavelength_pdf.coverage import REFUSE_OUTSIDE_FRACTION, check_range

    sp = make_spectrum("bump", "test", [365, 370, 375, 400, 700],
                       [0.0, 20.0, 0.0, 1.0, 1.0])  # a UV bump beside a flat band
    cov = coverage(np.array([380.0, 780.0]), np.ones((4, 2)), sp)
    assert cov.outside_matters
    assert max(cov.outside_luminance_fraction, cov.outside_tristimulus_fraction) < REFUSE_OUTSIDE_FRACTION
    (w,) = check_range(sp, 380.0, 780.0)
    assert "outside the table's range [380, 780] nm" in w
    assert check_range(_flat(400, 700), 380.0, 780.0) == []
