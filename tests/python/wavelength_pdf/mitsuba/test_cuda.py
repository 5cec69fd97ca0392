"""The cuda variant runs the same plugin code: where a CUDA device is present, the sensor draws
the vectors' wavelengths and weights and a scene renders; elsewhere the test skips."""
from __future__ import annotations

import numpy as np

from mitsuba_helpers import variant
from test_texture import draw, sensor_with_table
from wavelength_pdf import sampling
from wavelength_pdf.table import read_table


def test_cuda_spectral_draws_sample_four_and_renders(vectors, vector_table):
    mi, m = variant("cuda_ad_spectral")  # skips without a CUDA device
    wl, w = draw(mi, sensor_with_table(mi, vector_table), vectors[:, 0].astype(np.float32).astype(np.float64))
    t = read_table(vector_table)
    u = vectors[:, 0].astype(np.float32).astype(np.float64)
    lam = np.asarray(sampling.sample_four(t.grid, t.pdfs, u)).T
    np.testing.assert_allclose(wl, lam, rtol=2e-7)
    np.testing.assert_allclose(w, 1.0 / np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam)), rtol=2e-6)
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
                          "sensor": {"type": "perspective",
                                     "srf": {"type": "wavelength_table", "filename": str(vector_table)},
                                     "film": {"type": "hdrfilm", "width": 8, "height": 8},
                                     "sampler": {"type": "independent", "sample_count": 16}},
                          "light": {"type": "constant"}})
    img = np.asarray(mi.render(scene))
    assert np.all(np.isfinite(img)) and img.mean() > 0
