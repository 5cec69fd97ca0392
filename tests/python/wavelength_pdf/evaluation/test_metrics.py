"""Per-pixel CIEDE2000 of the evaluation (design §6): linear RGB -> XYZ -> Lab (D65, Y = 1)."""
from __future__ import annotations

import colour
import numpy as np
import pytest

from wavelength_pdf.evaluation.metrics import ErrorStats, delta_e_map, rgb_to_xyz


def test_identical_images_have_zero_error() -> None:
    img = np.random.default_rng(1).uniform(0, 2, (5, 7, 3))
    assert np.all(delta_e_map(img, img) == 0)


def test_against_colour_science_pixel_by_pixel() -> None:
    rng = np.random.default_rng(2)
    a, b = rng.uniform(0, 1.5, (2, 4, 6, 3))
    got = delta_e_map(a, b)
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    for i in range(4):
        for j in range(6):
            # No decoding: the sRGB matrix on the linear values, then Lab with white Y = 1.
            xyz = [colour.RGB_to_XYZ(p, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False)
                   for p in (a[i, j], b[i, j])]
            want = colour.delta_E(colour.XYZ_to_Lab(xyz[0], d65), colour.XYZ_to_Lab(xyz[1], d65),
                                  method="CIE 2000")
            assert got[i, j] == pytest.approx(want, rel=1e-9)


def test_white_maps_to_d65() -> None:
    xyz = rgb_to_xyz(np.ones(3))
    assert xyz[1] == pytest.approx(1.0, rel=1e-6)
    assert xyz[0] / xyz.sum() == pytest.approx(0.3127, abs=1e-4)


def test_stats_and_bad_input() -> None:
    s = ErrorStats.of(np.arange(101, dtype=float))
    assert (s.mean, s.median, s.p95) == (50.0, 50.0, 95.0)
    with pytest.raises(ValueError, match="shape"):
        delta_e_map(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))
    bad = np.zeros((2, 2, 3))
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        delta_e_map(bad, np.zeros((2, 2, 3)))
