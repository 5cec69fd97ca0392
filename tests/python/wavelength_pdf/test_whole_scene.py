"""One table for a whole scene (design §3.1, §5.6): the scene's total emission as the renderer
computes it, the table optimized for it covers every lamp, and the bad inputs."""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf import cli
from wavelength_pdf.result import read_header
from wavelength_pdf.scene_spectra import scene_spectra, whole_scene_spectrum
from wavelength_pdf.spectra import SpectrumError
from wavelength_pdf.table import read_table
from repo_paths import REPO  # noqa: E402

DATA = REPO / "tests" / "data"
SCENE = DATA / "scenes" / "two-lamps.pbrt"


def luminance(sp) -> float:
    """pbrt-v4's 1-nit normalization: the sum of the spectrum times ybar at 360..830 nm."""
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    lam = np.arange(360.0, 831.0)
    return float(np.sum(sp(lam) * np.array([cmfs[v][1] for v in lam])))


def test_whole_scene_spectrum_weights_each_lamp_by_its_power(pbrt):
    lamps = scene_spectra(SCENE)
    assert len(lamps) == 2
    total = whole_scene_spectrum(SCENE, pbrt=pbrt)
    lam = total.wavelengths
    # Line lamp: pi * area 2 * two-sided 2 * scale 3; broad lamp: pi * area 1 * scale 1.
    hand = (math.pi * 2 * 2 * 3 * lamps[0](lam) / luminance(lamps[0])
            + math.pi * lamps[1](lam) / luminance(lamps[1]))
    np.testing.assert_allclose(total.values, hand, rtol=1e-6, atol=1e-9 * hand.max())
    assert total.name == "two-lamps-whole-scene"


def test_whole_scene_table_covers_every_lamp(pbrt, tmp_path, monkeypatch):
    """The real optimizer (small budget): one table, accepted, whose mixture density is
    positive wherever either lamp emits, so that both lamps' estimates are unbiased."""
    from wavelength_pdf import evaluate_table

    monkeypatch.setenv("WAVELENGTH_PDF_PBRT", str(pbrt))
    out = tmp_path / "scene.csv"
    code = cli.main(["optimize", str(SCENE), "--whole-scene", "-o", str(out), "--grid-step", "10",
                     "--max-evals", "40", "--quiet"])
    assert code == 0
    t = read_table(out)
    assert read_header(t)["name"] == "two-lamps-whole-scene"
    for lamp in scene_spectra(SCENE):
        lam = np.linspace(380.0, 780.0, 40001)
        emits = lamp(lam) > 0
        mixture = sum(np.interp(lam, t.grid, p) for p in t.pdfs)
        assert emits.any() and np.all(mixture[emits] > 0), lamp.name
        assert evaluate_table(lamp, t).bias_rel <= 1e-6, lamp.name


def test_a_scene_without_emitters_is_refused(pbrt, tmp_path, capsys):
    dark = tmp_path / "dark.pbrt"
    dark.write_text('WorldBegin\nShape "sphere"\n')
    with pytest.raises(SpectrumError, match="no emitters"):
        whole_scene_spectrum(dark, pbrt=pbrt)
    out = tmp_path / "t.csv"
    assert cli.main(["optimize", str(dark), "--whole-scene", "--pbrt", str(pbrt), "-o", str(out),
                     "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(dark) in err and "no emitters" in err and not out.exists()


@pytest.mark.parametrize("argv, message", [
    (["cie:FL2", "--whole-scene"], "--whole-scene needs a pbrt-v4 scene"),
    (["cie:FL2", "--pbrt", "x"], "--pbrt is only used with a scene"),
    (["{scene}", "--whole-scene", "--pbrt", "/no/such/pbrt"], "not an executable file"),
    (["/no/such.pbrt", "--whole-scene"], "no such scene file"),
])
def test_bad_whole_scene_input_exits_2(tmp_path, capsys, argv, message):
    argv = [a.replace("{scene}", str(SCENE)) for a in argv]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = cli.main(["optimize", *argv, "-o", str(tmp_path / "t.csv"), "--quiet"])
    assert code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "t.csv").exists()


def test_scene_reflectances_are_the_materials_the_renderer_builds(pbrt):
    from wavelength_pdf.reflectances import scene_reflectances

    s = scene_reflectances(SCENE, pbrt=pbrt)
    # The quads use pbrt-v4's default material (constant 0.5), the floor an RGB albedo.
    assert s.labels[0] == "default material" and len(s) == 2
    np.testing.assert_allclose(s.values[0], 0.5, rtol=1e-6)
    floor = s.values[1]
    assert np.all((floor >= 0) & (floor <= 1))
    assert np.interp(650, s.wavelengths, floor) > 2 * np.interp(450, s.wavelengths, floor)


def test_whole_scene_with_the_scenes_reflectances_end_to_end(pbrt, tmp_path, monkeypatch):
    monkeypatch.setenv("WAVELENGTH_PDF_PBRT", str(pbrt))
    out = tmp_path / "t.csv"
    code = cli.main(["optimize", str(SCENE), "--whole-scene", "--reflectances", "scene", "-o",
                     str(out), "--grid-step", "20", "--max-evals", "20", "--quiet"])
    assert code == 0
    hdr = read_header(read_table(out))
    assert hdr["name"] == "two-lamps-whole-scene" and "reflectances: scene (2 colours" in hdr["source"]


def test_a_scene_without_diffuse_materials_has_no_reflectances(pbrt, tmp_path, capsys):
    glass = tmp_path / "glass.pbrt"
    glass.write_text('WorldBegin\nLightSource "point"\nMaterial "dielectric"\nShape "sphere"\n')
    assert cli.main(["optimize", str(glass), "--reflectances", "scene", "--pbrt", str(pbrt),
                     "-o", str(tmp_path / "t.csv"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(glass) in err and "non-zero diffuse reflectance" in err


def test_a_scene_is_optimized_for_its_own_materials_by_default(pbrt, tmp_path, monkeypatch, capsys):
    """Without --reflectances, optimize SCENE.pbrt takes the scene's materials (design §4.5);
    without a renderer it warns and optimizes for the white surface; 'white' asks for it."""
    import wavelength_pdf.cli.optimize as opt

    seen = []
    real = opt.optimize_one

    def spy(*a, reflectances=None, **kw):
        seen.append(None if reflectances is None else reflectances.name)
        return real(*a, reflectances=reflectances, **kw)

    monkeypatch.setattr(opt, "optimize_one", spy)
    argv = ["optimize", f"{SCENE}#0", "-o", str(tmp_path / "t.csv"), "--grid-step", "20",
            "--max-evals", "5", "--quiet"]
    monkeypatch.setenv("WAVELENGTH_PDF_PBRT", str(pbrt))
    cli.main(argv)
    cli.main(argv + ["--reflectances", "white"])
    monkeypatch.setenv("WAVELENGTH_PDF_PBRT", str(tmp_path / "no-pbrt"))
    monkeypatch.setattr("wavelength_pdf.renderer.in_checkout", lambda: False)
    monkeypatch.setenv("PATH", str(tmp_path))
    cli.main(argv)
    assert seen == ["scene", None, None]
    assert "optimizing for a white surface" in capsys.readouterr().err
