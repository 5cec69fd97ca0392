"""Emission sampling in Mitsuba 3 (``wavelength_pdf.mitsuba.emission_srf``, design §1.7, §8.3).

(a) The emitted power is pbrt-v4's light power, emitter by emitter, against hand formulas: an
    area emitter pi A L, a point light 4 pi I, a spot light (its falloff integrated numerically
    from Mitsuba's own intensities), a directional emitter pi r^2 E, a constant environment
    4 pi^2 r^2 L, an environment map of one grey value 4 pi^2 r^2 c D65; the table of a scene with
    one lamp is the stratified table of the lamp's spectrum.
(b) The srf draws that table: its wavelengths and weights are SampleFour's.
(c) Unbiased: on the Mitsuba Cornell box under the tri-band lamp, images with the emission srf
    converge to Mitsuba's default sampling (llvm and scalar; cuda where a device exists).
(d) Bad input: no emitters, no power, an unknown weight, a table name that was never built.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from mitsuba_helpers import SCENE, TRIBAND, variant
from wavelength_pdf import sampling, stratified
from wavelength_pdf.evaluation import render_mitsuba as rm
from wavelength_pdf.mitsuba import EmissionError, emission_srf, emission_table, emitted_power
from wavelength_pdf.spectra import Spectrum, load_spectrum

VARIANTS = ["scalar_spectral", "llvm_ad_spectral"]
LAM = np.array([380.0, 450.0, 546.0, 611.0, 700.0, 829.0])


_SCENES: dict[str, tuple[object, dict]] = {}


def cornell(mi, tmp: Path, size: int = 8) -> tuple[object, dict]:
    """The Mitsuba Cornell box under the tri-band lamp, loaded once per variant."""
    if mi.variant() not in _SCENES:
        params = rm.scene_params(SCENE, load_spectrum(str(TRIBAND)), 380.0, 780.0, (size, size))
        xml = rm.write_variant(SCENE, tmp / "cornell.xml", "visible", None, 380.0, 780.0)
        _SCENES[mi.variant()] = (mi.load_file(str(xml), **params), params)
    return _SCENES[mi.variant()]


def mixture(table, x: np.ndarray) -> np.ndarray:
    """(1/4) sum_k p_k(x), each density linear between the nodes."""
    return np.mean([np.interp(x, table.grid, p, left=0.0, right=0.0) for p in table.pdfs], axis=0)


def power_at(phi: Spectrum, lam=LAM) -> np.ndarray:
    return np.interp(lam, phi.wavelengths, phi.values)


# ---------------------------------------------------------------------------------------------
# (a) Power
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", VARIANTS)
def test_power_of_each_emitter_type(name):
    mi, _ = variant(name)
    d65 = mi.load_dict({"type": "d65"})

    def d65_at(lam):
        import drjit as dr

        out = []
        for l in lam:
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wavelengths = type(si.wavelengths)(float(l), float(l), float(l), float(l))
            out.append(float(np.asarray(d65.eval(si)[0]).ravel()[0]))
        return np.array(out)

    r = 3.0
    # A 2 x 2 rectangle scaled by 1.5 in x: area 6.
    area = mi.load_dict({"type": "scene", "s": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([1.5, 1, 1]),
                                                "emitter": {"type": "area", "radiance": {"type": "uniform", "value": 1.5}}}})
    np.testing.assert_allclose(power_at(emitted_power(area)), math.pi * 6 * 1.5, rtol=1e-5)
    point = mi.load_dict({"type": "point", "position": [0, 1, 2], "intensity": {"type": "uniform", "value": 2.0}})
    np.testing.assert_allclose(power_at(emitted_power([point])), 4 * math.pi * 2.0, rtol=1e-5)
    directional = mi.load_dict({"type": "directional", "direction": [0, 0, 1], "irradiance": {"type": "uniform", "value": 0.7}})
    np.testing.assert_allclose(power_at(emitted_power([directional], radius=r)), math.pi * r * r * 0.7, rtol=1e-5)
    constant = mi.load_dict({"type": "constant", "radiance": {"type": "uniform", "value": 0.5}})
    np.testing.assert_allclose(power_at(emitted_power([constant], radius=r)), 4 * math.pi ** 2 * r * r * 0.5, rtol=1e-5)
    grey = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(np.full((16, 32, 3), 0.25, dtype=np.float32))})
    np.testing.assert_allclose(power_at(emitted_power([grey], radius=r)),
                               4 * math.pi ** 2 * r * r * 0.25 * d65_at(LAM), rtol=1e-4)
    # A spot light: the closed form against Mitsuba's own falloff, integrated over the sphere.
    spot = mi.load_dict({"type": "spot", "intensity": {"type": "uniform", "value": 3.0},
                         "cutoff_angle": 35.0, "beam_width": 15.0})
    theta = (np.arange(4000) + 0.5) * math.pi / 4000
    falloff = []
    import drjit as dr
    for t in theta[::40]:
        it = dr.zeros(mi.Interaction3f)
        it.p = mi.Point3f(math.sin(t), 0.0, math.cos(t))
        it.wavelengths = type(it.wavelengths)(550.0, 550.0, 550.0, 550.0)
        falloff.append(float(np.asarray(spot.sample_direction(it, mi.Point2f(0.5, 0.5))[1][0]).ravel()[0]))
    t = theta[::40]
    numeric = 2 * math.pi * np.sum(np.array(falloff) * np.sin(t)) * (math.pi / len(t))
    np.testing.assert_allclose(power_at(emitted_power([spot]), [550.0]), numeric, rtol=2e-3)


@pytest.mark.parametrize("name", VARIANTS)
def test_one_lamp_gives_the_stratified_table_of_its_spectrum(name, tmp_path):
    mi, _ = variant(name)
    scene, params = cornell(mi, tmp_path)
    lam = np.array([float(v) for v in params["lamp_wavelengths"].split(",")])
    val = np.array([float(v) for v in params["lamp_values"].split(",")])
    phi = emitted_power(scene)
    # Every node of the lamp (Mitsuba holds them in single precision) is a node of Phi.
    assert np.all(np.isin(lam.astype(np.float32), phi.wavelengths.astype(np.float32)))
    ref = stratified.stratified_table(Spectrum("lamp", "lamp", lam, val), "spd", 360.0, 830.0)
    t = emission_table(scene)
    x = np.linspace(360.0, 830.0, 20_001)
    np.testing.assert_allclose(mixture(t, x), mixture(ref, x), rtol=1e-5, atol=1e-7 * ref.pdfs.max())
    for w in ("luminance", "xyz"):  # the weights multiply the same emission
        tw = emission_table(scene, w)
        np.testing.assert_allclose(tw.grid, stratified.stratified_table(phi, w, 360.0, 830.0).grid)


# ---------------------------------------------------------------------------------------------
# (b) The srf draws the table
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", VARIANTS)
def test_emission_srf_draws_the_emission_table(name, tmp_path):
    mi, _ = variant(name)
    from test_texture import draw

    scene, _ = cornell(mi, tmp_path)
    srf = emission_srf(scene)
    sensor = mi.load_dict({"type": "perspective", "srf": srf})
    t = emission_table(scene)
    u = np.linspace(0.0, 1.0, 257)[1:-1].astype(np.float32).astype(np.float64)
    wl, w = draw(mi, sensor, u)
    lam = np.asarray(sampling.sample_four(t.grid, t.pdfs, u)).T
    np.testing.assert_allclose(wl, lam, rtol=2e-7)
    np.testing.assert_allclose(w, 1.0 / np.asarray(sampling.mixture_pdf(t.grid, t.pdfs, lam)), rtol=2e-6)


# ---------------------------------------------------------------------------------------------
# (c) Unbiased
# ---------------------------------------------------------------------------------------------

def emission_xml(mi, tmp: Path, params: dict, name: str) -> Path:
    """The Cornell box (ldsampler) whose sensor's srf is emission_srf of the scene itself."""
    base = rm.write_variant(SCENE, tmp / f"base-{name}.xml", "visible", None, 380.0, 780.0, sampler="ldsampler")
    srf = emission_srf(mi.load_file(str(base), **params))
    root = ET.parse(base).getroot()
    el = ET.Element("texture", type=srf["type"], name="srf")
    ET.SubElement(el, "string", name="table", value=srf["table"])
    root.find("sensor").insert(0, el)
    out = tmp / f"emission-{name}.xml"
    ET.ElementTree(root).write(out, encoding="unicode")
    return out


@pytest.mark.slow
# Emission sampling is far less noisy than the default here: its spp is a quarter of the
# table test's (test_unbiased), and the default renders are that module's (shared cache).
@pytest.mark.parametrize("name, spp, default_spp", [("llvm_ad_spectral", 256, 2048), ("scalar_spectral", 32, 512)])
def test_emission_srf_converges_to_mitsuba_default(name, spp, default_spp, tmp_path):
    import test_unbiased as tu

    mi, _ = variant(name)
    spectrum = load_spectrum(str(TRIBAND))
    params = rm.scene_params(SCENE, spectrum, tu.LO, tu.HI, (tu.RES, tu.RES))
    xml = emission_xml(mi, tmp_path, params, name)
    em = [rm.render_image(xml, params, spp, seed, name) for seed in tu.SEEDS]
    default = tu.renders(tmp_path, name, spectrum, "visible", None, default_spp, tu.SEEDS)
    tu.check_same_expectation(em, default, f"{name}: emission srf vs Mitsuba's default", heavy_tailed=True)
    me, se = tu.mean_and_se(em)
    md, sd = tu.mean_and_se(default)
    print(f"{name}: emission vs default z = {np.round((me - md) / np.hypot(se, sd), 2)}; "
          f"se of the mean, emission {np.round(se / me, 4)}, default {np.round(sd / md, 4)}")


def test_cuda_emission_srf_renders(tmp_path):
    mi, _ = variant("cuda_ad_spectral")  # skips without a CUDA device
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
                          "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 8, "height": 8},
                                     "sampler": {"type": "independent", "sample_count": 16}},
                          "light": {"type": "constant"}})
    srf = emission_srf(scene)
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
                          "sensor": {"type": "perspective", "srf": srf, "film": {"type": "hdrfilm", "width": 8, "height": 8},
                                     "sampler": {"type": "independent", "sample_count": 16}},
                          "light": {"type": "constant"}})
    img = np.asarray(mi.render(scene))
    assert np.all(np.isfinite(img)) and img.mean() > 0


# ---------------------------------------------------------------------------------------------
# (d) Bad input
# ---------------------------------------------------------------------------------------------

def test_bad_input_is_refused_with_a_reason():
    mi, _ = variant("scalar_spectral")
    with pytest.raises(EmissionError, match="no emitters"):
        emitted_power(mi.load_dict({"type": "scene", "s": {"type": "sphere"}}))
    dark = mi.load_dict({"type": "point", "intensity": {"type": "uniform", "value": 0.0}})
    with pytest.raises(EmissionError, match="emits between 360 and 830 nm"):
        emitted_power([dark])
    bright = mi.load_dict({"type": "point", "intensity": {"type": "uniform", "value": 1.0}})
    with pytest.raises(EmissionError, match="unknown weight"):
        emission_table([bright], "ybar")
    with pytest.raises(EmissionError, match="needs the scene's radius"):
        emitted_power([mi.load_dict({"type": "constant"})])
    from wavelength_pdf.table import TableError
    with pytest.raises((RuntimeError, EmissionError, TableError), match="no emission table"):
        mi.load_dict({"type": "perspective", "srf": {"type": "wavelength_table", "table": "emission-nothing"}})
