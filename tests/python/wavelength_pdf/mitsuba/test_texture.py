"""The ``wavelength_table`` texture, used as a sensor's ``srf``, makes Mitsuba draw exactly the
header's ``SampleFour``: the same u for the four lanes, weight 1 / mixture pdf; in a scene dict
and in XML; and a bad table fails scene loading with ``FILE:LINE: reason``."""
from __future__ import annotations

import numpy as np
import pytest

from input_files import EDGE_TABLES, edge_table_cases
from mitsuba_helpers import SCENE, variant
from wavelength_pdf import sampling
from wavelength_pdf.mitsuba import register
from wavelength_pdf.table import read_table

VARIANTS = ["scalar_spectral", "llvm_ad_spectral", "scalar_spectral_polarized", "llvm_ad_spectral_polarized"]


def sensor_with_table(mi, table, **extra):
    return mi.load_dict({"type": "perspective",
                         "srf": {"type": "wavelength_table", "filename": str(table), **extra}})


def draw(mi, sensor, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wavelengths and weights (one row per u, lanes 0..3) from the sensor itself."""
    import drjit as dr

    si = dr.zeros(mi.SurfaceInteraction3f)
    polarized = "polarized" in mi.variant()

    def arrays(wl, w):
        w = np.array(w)
        return np.array(wl), (w[0, 0] if polarized else w)  # a Mueller matrix: the unpolarized weight

    if dr.is_jit_v(mi.Float):
        wl, w = arrays(*sensor.sample_wavelengths(si, mi.Float(u)))
        return wl.T, w.T
    pairs = [arrays(*sensor.sample_wavelengths(si, float(x))) for x in u]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


@pytest.mark.parametrize("name", VARIANTS)
def test_sensor_draws_sample_four(name, vectors, vector_table):
    mi, _ = variant(name)
    sensor = sensor_with_table(mi, vector_table)
    u32 = vectors[:, 0].astype(np.float32)  # Mitsuba's samples are single precision
    wl, w = draw(mi, sensor, u32.astype(np.float64))
    t = read_table(vector_table)
    u = u32.astype(np.float64)
    lam = np.asarray(sampling.sample_four(t.grid, t.pdfs, u)).T
    mix = np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam))
    # float32 wavelengths and weights of the double-precision result at the same u
    np.testing.assert_allclose(wl, lam, rtol=2e-7)
    np.testing.assert_allclose(w, 1.0 / mix, rtol=2e-6)
    # where float32(u) == u the drawn wavelengths are the committed vectors themselves
    same = u32.astype(np.float64) == vectors[:, 0]
    assert same.sum() >= 30  # u = 0, 1, dyadic u and CDF nodes that float32 holds exactly
    np.testing.assert_allclose(wl[same], vectors[same, 1:5], rtol=2e-7)
    np.testing.assert_allclose(w[same], 1.0 / vectors[same, 5:9], rtol=2e-6)


@pytest.mark.parametrize("name", ["scalar_spectral", "llvm_ad_spectral"])
def test_defensive_property(name, vector_table):
    mi, _ = variant(name)
    sensor = sensor_with_table(mi, vector_table, defensive=0.25)
    t = read_table(vector_table)
    lo, hi = t.grid[0], t.grid[-1]
    pdfs = 0.75 * t.pdfs + 0.25 / (hi - lo)
    u = np.array([0.0, 0.1, 0.5, 0.9, 1.0 - 2**-24], dtype=np.float32).astype(np.float64)
    wl, w = draw(mi, sensor, u)
    lam = np.asarray(sampling.sample_four(t.grid, pdfs, u)).T
    np.testing.assert_allclose(wl, lam, rtol=2e-7)
    np.testing.assert_allclose(w, 1.0 / np.asarray(sampling.mixture_pdf(t.grid, pdfs, lam)), rtol=2e-6)


@pytest.mark.parametrize("name", ["scalar_spectral", "llvm_ad_spectral"])
def test_bad_table_fails_scene_loading_with_file_line_reason(name, tmp_path):
    mi, _ = variant(name)
    bad = tmp_path / "bad.csv"
    bad.write_text("# a table\nlambda_nm,pdf0,pdf1,pdf2,pdf3\n400,1,1,1,1\n500,1,nan,1,1\n")
    with pytest.raises(Exception, match=rf"{bad}:4: pdf1 is NaN at 500 nm"):
        sensor_with_table(mi, bad)
    with pytest.raises(Exception, match=r"no such file"):
        sensor_with_table(mi, tmp_path / "missing.csv")
    with pytest.raises(Exception, match="needs a 'filename'"):
        mi.load_dict({"type": "perspective", "srf": {"type": "wavelength_table"}})


@pytest.mark.parametrize("name", ["scalar_spectral", "llvm_ad_spectral"])
def test_edge_tables_load_as_every_reader_reads_them(name):
    """The shared edge cases (tests/data/tables/edge): the plugin refuses what pbrt and the
    header refuse, at the same line, and samples what they read; a table of subnormal
    densities (5e-324 everywhere) is uniform sampling, not "zero everywhere"."""
    mi, _ = variant(name)
    u = np.array([0.0, 0.1, 0.5, 0.9, 1.0 - 2**-24], dtype=np.float32).astype(np.float64)
    for file, nodes, line, reason in edge_table_cases():
        path = EDGE_TABLES / file
        if nodes is None:
            with pytest.raises(Exception) as e:
                sensor_with_table(mi, path)
            assert f"{path}:{line}: " in str(e.value) and reason in str(e.value), (file, str(e.value))
            continue
        wl, w = draw(mi, sensor_with_table(mi, path), u)
        t = read_table(path)
        lam = np.asarray(sampling.sample_four(t.grid, t.pdfs, u)).T
        np.testing.assert_allclose(wl, lam, rtol=2e-7, err_msg=file)
        np.testing.assert_allclose(w, 1.0 / np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam)),
                                   rtol=2e-6, err_msg=file)
    wl, w = draw(mi, sensor_with_table(mi, EDGE_TABLES / "denormal.csv"), u)
    t = read_table(EDGE_TABLES / "denormal.csv")
    np.testing.assert_allclose(w, t.grid[-1] - t.grid[0], rtol=1e-6)  # 1 / the uniform density


def test_xml_scene_renders_with_the_table(tmp_path, vector_table):
    """The Cornell box's XML with the texture in its sensor loads and renders (llvm)."""
    mi, _ = variant("llvm_ad_spectral")
    xml = SCENE.read_text().replace(
        '<sensor type="perspective">',
        '<sensor type="perspective">\n<texture type="wavelength_table" name="srf">'
        f'<string name="filename" value="{vector_table}"/><float name="defensive" value="0.05"/></texture>')
    path = SCENE.parent / f".test-{tmp_path.name}.xml"  # beside the meshes it names
    try:
        path.write_text(xml)
        scene = mi.load_file(str(path), width="8", height="8", spp="16")
    finally:
        path.unlink(missing_ok=True)
    img = np.asarray(mi.render(scene, seed=1))
    assert img.shape == (8, 8, 3) and np.all(np.isfinite(img)) and img.mean() > 0


def test_register_rejects_non_spectral_variants():
    with pytest.raises(ValueError, match="not a spectral variant"):
        register("scalar_rgb")
    with pytest.raises(ValueError, match="not a spectral variant"):
        register("no_such_variant")
