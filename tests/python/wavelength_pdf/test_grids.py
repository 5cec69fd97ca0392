"""Adaptive table grids for line lamps."""

import numpy as np

import wavelength_pdf  # noqa: F401  (enables float64)
from wavelength_pdf import grids
from wavelength_pdf.model import DEFAULT_GRID
from wavelength_pdf.problem import make_problem
from wavelength_pdf.spectra import Spectrum

WL = np.arange(380.0, 781.0, 0.5)


def _lines():
    val = 0.02 + sum(np.exp(-0.5 * ((WL - c) / 0.8) ** 2) for c in (436.0, 546.0, 611.0))
    return Spectrum("lines", "test:lines", WL, val)


def _smooth():
    return Spectrum("smooth", "test:smooth", WL, 1.0 + 0.5 * np.sin(WL / 40.0))


def test_line_lamps_are_told_apart_from_smooth_spectra():
    lines = make_problem(_lines())
    smooth = make_problem(_smooth())
    assert grids.is_spiky(lines) and not grids.is_spiky(smooth)
    assert grids.interpolation_error(smooth, DEFAULT_GRID) < 0.01


def test_refine_adds_nodes_around_the_lines_only():
    p = make_problem(_lines())
    base = DEFAULT_GRID
    g = grids.refine(p, base, 161, 1.25)
    assert g.size == 161
    assert np.all(np.isin(base, g))  # a table on the base grid is representable exactly
    assert np.min(np.diff(g)) >= 1.25 - 1e-9
    # The lines get the finest steps first, and a node close to each peak (splits are
    # made at the breakpoint furthest from the chord).
    for c in (436.0, 546.0, 611.0):
        near = (g[:-1] >= c - 3.0) & (g[1:] <= c + 3.0)
        assert np.any(near) and np.all(np.diff(g)[near] <= 2.5), c
        assert np.min(np.abs(g - c)) <= 0.5, c
    # Where the lamp is a flat continuum, the default 5 nm steps stay.
    far = (g[:-1] >= 660.0) & (g[1:] <= 780.0)
    assert np.all(np.diff(g)[far] >= 2.0)
    assert grids.interpolation_error(p, g) < 0.3 * grids.interpolation_error(p, base)
    # Splitting reduces the error segment by segment.
    assert grids.interpolation_error(p, grids.refine(p, base, 121, 1.25)) > grids.interpolation_error(p, g)
    # Errors of a grid's segments add up to its total error.
    assert np.sum(grids.segment_errors(p, g)) == grids.interpolation_error(p, g)


def test_refine_stops_at_the_smallest_step():
    p = make_problem(_lines())
    g = grids.refine(p, np.array([430.0, 440.0]), 1000, 2.5)
    assert g.size < 1000 and np.min(np.diff(g)) >= 2.5 - 1e-9


def test_refine_stops_at_the_target_error_and_fill_to_reaches_the_bucket():
    p = make_problem(_lines())
    base = DEFAULT_GRID
    g = grids.refine(p, base, 481, grids.MIN_STEP_NM, target_error=0.01)
    assert g.size < 481 and grids.interpolation_error(p, g) <= 0.01
    f = grids.fill_to(g, grids.bucket(g.size))
    assert f.size == grids.bucket(g.size) and np.all(np.isin(g, f))
    assert grids.bucket(10) == grids.BUCKETS[0] and grids.bucket(10**6) == grids.BUCKETS[-1]
