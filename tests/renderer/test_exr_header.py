"""The renderer's EXR images say what they are: the film's colour space (the standard
``chromaticities`` attribute) and how they were made (spp, seed, wavelength sampler, the table
and its SHA-256, render time), read back through ``wavelength_pdf.exr.read_header``."""
from __future__ import annotations

import hashlib
import subprocess

import numpy as np
import pytest

from wavelength_pdf.exr import ImageError, read_header, read_rgb

# CIE 1931 xy of the red, green, blue primaries: ITU-R BT.2020 and BT.709 (sRGB); both D65.
REC2020 = (0.708, 0.292, 0.170, 0.797, 0.131, 0.046)
SRGB = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06)
D65 = (0.3127, 0.3290)

SCENE = """
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [20]
Film "rgb" "integer xresolution" [4] "integer yresolution" [4]
Sampler "independent" "integer pixelsamples" [2]
WorldBegin
LightSource "infinite" "rgb L" [1 0.5 0.25]
"""


def render(pbrt, tmp_path, name: str, scene: str, *args: str):
    src = tmp_path / f"{name}.pbrt"
    src.write_text(scene)
    out = tmp_path / f"{name}.exr"
    r = subprocess.run([str(pbrt), "--quiet", "--outfile", str(out), *args, str(src)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return out


def test_a_rec2020_render_carries_rec2020_chromaticities(pbrt, tmp_path):
    rec = read_header(render(pbrt, tmp_path, "rec2020", 'ColorSpace "rec2020"\n' + SCENE))
    srgb = read_header(render(pbrt, tmp_path, "srgb", SCENE))
    np.testing.assert_allclose(rec["chromaticities"][:6], REC2020, atol=1e-6)
    np.testing.assert_allclose(rec["chromaticities"][6:], D65, atol=2e-4)
    assert rec["colorSpace"] == "rec2020"
    # The default colour space is sRGB, and it says so too.
    np.testing.assert_allclose(srgb["chromaticities"][:6], SRGB, atol=1e-6)
    assert srgb["colorSpace"] == "srgb"


def test_provenance_of_a_table_render(pbrt, repo, tmp_path):
    table = repo / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
    exr = render(pbrt, tmp_path, "table", SCENE, "--spp", "3", "--seed", "5000000000",
                 "--wavelength-pdf", str(table), "--wavelength-pdf-defensive", "0.125")
    h = read_header(exr)
    assert h["samplesPerPixel"] == 3
    assert h["seed"] == "5000000000"
    assert h["wavelengthSampler"] == "table"
    assert h["wavelengthTable"] == str(table)
    assert h["wavelengthTableSHA256"] == hashlib.sha256(table.read_bytes()).hexdigest()
    assert h["wavelengthDefensiveShare"] == pytest.approx(0.125)
    assert h["renderTimeSeconds"] > 0
    assert read_rgb(exr).shape == (4, 4, 3)


def test_provenance_of_builtin_sampling(pbrt, tmp_path):
    h = read_header(render(pbrt, tmp_path, "uniform", SCENE, "--wavelength-sampling", "uniform",
                           "--wavelength-range", "400", "700"))
    assert h["samplesPerPixel"] == 2
    assert h["seed"] == "0"
    assert h["wavelengthSampler"] == "uniform"
    np.testing.assert_allclose(h["wavelengthRange"], (400, 700))
    assert "wavelengthTable" not in h and "wavelengthTableSHA256" not in h
    h = read_header(render(pbrt, tmp_path, "visible", SCENE))
    assert h["wavelengthSampler"] == "visible"
    np.testing.assert_allclose(h["wavelengthRange"], (360, 830))


def test_provenance_of_emission_sampling(pbrt, tmp_path):
    """--wavelength-sampling emission records its kind and weight, and no table file."""
    for weight in ("spd", "xyz"):
        h = read_header(render(pbrt, tmp_path, f"emission-{weight}", SCENE, "--wavelength-sampling",
                               "emission", "--emission-weight", weight))
        assert h["wavelengthSampler"] == "emission"
        assert h["wavelengthEmissionWeight"] == weight
        np.testing.assert_allclose(h["wavelengthRange"], (360, 830))
        assert "wavelengthTable" not in h and "wavelengthTableSHA256" not in h
    h = read_header(render(pbrt, tmp_path, "emission-default", SCENE, "--wavelength-sampling", "emission"))
    assert h["wavelengthEmissionWeight"] == "spd"  # the default weight


def test_read_header_rejects_what_is_not_exr(tmp_path):
    with pytest.raises(ImageError, match="no such image file"):
        read_header(tmp_path / "missing.exr")
    (tmp_path / "text.exr").write_text("not an image")
    with pytest.raises(ImageError, match="cannot read as OpenEXR"):
        read_header(tmp_path / "text.exr")
