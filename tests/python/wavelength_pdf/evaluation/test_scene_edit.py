"""The evaluation's scene copy: every emitter lit by the given spectrum (cut to the range),
files named by absolute path, the film's resolution overridden, the rest untouched."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf.evaluation.scene_edit import edit_scene, inline_spectrum
from wavelength_pdf.scene_spectra import scan_scene
from wavelength_pdf.spectra import Spectrum, SpectrumError
from repo_paths import REPO  # noqa: E402

DATA = REPO / "tests" / "data" / "scenes"
LAMP = Spectrum("lamp", "test", np.array([300.0, 400.0, 546.0, 547.0, 548.0, 900.0]),
                np.array([5.0, 1.0, 0.0, 7.0, 0.0, 5.0]))


def test_every_emitter_gets_the_spectrum_cut_to_the_range(tmp_path: Path) -> None:
    out = edit_scene(DATA / "several.pbrt", LAMP, tmp_path / "copy.pbrt", lo=380, hi=780)
    emitters = scan_scene(out)
    # Every emitter of the original (including the RGB point light and the Included file's)
    # now carries the lamp, and nothing outside 380-780 nm.
    assert len(emitters) == len(scan_scene(DATA / "several.pbrt"))
    lam = np.linspace(380, 780, 801)
    want = np.interp(lam, LAMP.wavelengths, LAMP.values)
    for em in emitters:
        sp = em.spectrum
        assert sp is not None, em.reason
        got = np.interp(lam, sp.wavelengths, sp.values, left=0, right=0)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12, err_msg=em.where)
        assert np.interp(379.0, sp.wavelengths, sp.values, left=0, right=0) == 0
        assert np.interp(781.0, sp.wavelengths, sp.values, left=0, right=0) == 0


def test_film_resolution_and_file_paths(tmp_path: Path) -> None:
    src = tmp_path / "src"
    (src / "models").mkdir(parents=True)
    (src / "models" / "m.ply").write_text("ply\n")
    scene = src / "s.pbrt"
    scene.write_text('Film "rgb" "integer xresolution" [ 640 ] "string filename" "x.exr"\n'
                     '    "integer yresolution" [ 480 ]\n'
                     'WorldBegin\n'
                     'AttributeBegin\n  AreaLightSource "diffuse" "rgb L" [ 1 1 1 ] "float scale" [ 3 ]\n'
                     '  Shape "plymesh" "string filename" "models/m.ply"\nAttributeEnd\n'
                     'Shape "sphere" "float radius" [ 2 ]  # untouched\n')
    out = edit_scene(scene, LAMP, tmp_path / "out" / "copy.pbrt", resolution=(32, 24))
    text = out.read_text()
    assert '"integer xresolution" [ 32 ]' in text and '"integer yresolution" [ 24 ]' in text
    assert f'"{(src / "models" / "m.ply").resolve()}"' in text
    assert '"float scale" [ 3 ]' in text and 'Shape "sphere" "float radius" [ 2 ]  # untouched' in text
    assert '"rgb L"' not in text and '"spectrum L" [ 379.999 0 380 ' in text


def test_resolution_added_when_the_film_has_none(tmp_path: Path) -> None:
    scene = tmp_path / "s.pbrt"
    scene.write_text('Film "rgb"\nWorldBegin\nLightSource "point" "spectrum I" [ 400 1 700 1 ]\n')
    text = edit_scene(scene, None, tmp_path / "c.pbrt", resolution=(8, 6)).read_text()
    assert '"integer xresolution" [ 8 ] "integer yresolution" [ 6 ]' in text
    assert '"spectrum I" [ 400 1 700 1 ]' in text  # spectrum None keeps the emitters


def test_a_spectrum_without_energy_in_range_is_an_error(tmp_path: Path) -> None:
    dark = Spectrum("ir", "test", np.array([800.0, 900.0]), np.array([1.0, 1.0]))
    with pytest.raises(SpectrumError, match="no energy inside 380-780"):
        inline_spectrum(dark, 380, 780)


def test_resolution_scale_applies_to_the_scene_size_or_pbrt_default(tmp_path: Path) -> None:
    scene = tmp_path / "s.pbrt"
    scene.write_text('Film "rgb" "integer xresolution" [ 1024 ] "integer yresolution" [ 720 ]\nWorldBegin\n')
    text = edit_scene(scene, None, tmp_path / "c.pbrt", resolution=0.125).read_text()
    assert '"integer xresolution" [ 128 ]' in text and '"integer yresolution" [ 90 ]' in text
    # Only the height given: the width is pbrt-v4's default 1280, scaled; never below 1 pixel.
    scene.write_text('Film "rgb" "integer yresolution" [ 720 ]\nWorldBegin\n')
    text = edit_scene(scene, None, tmp_path / "c.pbrt", resolution=1e-4).read_text()
    assert '"integer xresolution" [ 1 ]' in text and '"integer yresolution" [ 1 ]' in text
    assert text.count("xresolution") == 1 and text.count("yresolution") == 1
    with pytest.raises(ValueError, match="positive"):
        edit_scene(scene, None, tmp_path / "c.pbrt", resolution=-1.0)


def test_maxdepth_replaced_or_added(tmp_path: Path) -> None:
    scene = tmp_path / "s.pbrt"
    scene.write_text('Integrator "path" "integer maxdepth" [ 17 ] "bool regularize" false\nWorldBegin\n')
    text = edit_scene(scene, None, tmp_path / "c.pbrt", maxdepth=5).read_text()
    assert '"integer maxdepth" [ 5 ]' in text and "17" not in text and '"bool regularize" false' in text
    scene.write_text('Integrator "bdpt"\nWorldBegin\n')
    text = edit_scene(scene, None, tmp_path / "c.pbrt", maxdepth=3).read_text()
    assert 'Integrator "bdpt" "integer maxdepth" [ 3 ]' in text and text.count("maxdepth") == 1
    # None keeps the scene's own
    scene.write_text('Integrator "path" "integer maxdepth" [ 17 ]\nWorldBegin\n')
    assert '"integer maxdepth" [ 17 ]' in edit_scene(scene, None, tmp_path / "c.pbrt").read_text()


def test_a_cut_spectrum_emits_nothing_outside_the_range(tmp_path: Path) -> None:
    """pbrt-v4 extends a spectrum's end values over its whole range; a cut one ends in zeros."""
    flat = Spectrum("flat", "test", np.array([300.0, 900.0]), np.array([2.0, 2.0]))
    numbers = [float(v) for v in inline_spectrum(flat, 380, 780).strip("[] ").split()]
    lam, val = numbers[0::2], numbers[1::2]
    assert (lam[0], val[0]) == (380 - 1e-3, 0.0) and (lam[-1], val[-1]) == (780 + 1e-3, 0.0)
    assert val[1:-1] == [2.0] * (len(val) - 2)


def test_cut_emitters_keeps_their_shape_inside_the_range(tmp_path: Path, pbrt) -> None:
    (tmp_path / "lamp.spd").write_text("300 1\n600 4\n900 1\n")
    scene = tmp_path / "s.pbrt"
    scene.write_text('Film "rgb" "integer xresolution" [ 4 ] "integer yresolution" [ 4 ]\nWorldBegin\n'
                     'LightSource "point" "spectrum I" [ 400 1 700 1 ] "float scale" [ 2 ]\n'
                     'AttributeBegin\n  AreaLightSource "diffuse" "spectrum L" "lamp.spd"\n'
                     '  Shape "sphere" "float radius" [ 1 ]\nAttributeEnd\n')
    out = edit_scene(scene, None, tmp_path / "c" / "c.pbrt", cut_emitters=True)
    import subprocess

    spd = tmp_path / "e.spd"
    subprocess.run([str(pbrt), "--quiet", "--emission-spectrum", str(spd), str(out)], check=True)
    lam, val = np.loadtxt(spd, comments="#").T
    assert np.all(val[(lam < 380 - 1e-3) | (lam > 780 + 1e-3)] == 0)
    inside = (lam >= 380) & (lam <= 780)
    assert np.all(val[inside] > 0)
    # Inside the range the cut emitters emit as before.
    whole = tmp_path / "w.spd"
    subprocess.run([str(pbrt), "--quiet", "--emission-spectrum", str(whole), str(scene)], check=True)
    lw, vw = np.loadtxt(whole, comments="#").T
    grid = np.linspace(381, 779, 50)
    np.testing.assert_allclose(np.interp(grid, lam, val), np.interp(grid, lw, vw), rtol=1e-5)
    scene.write_text('WorldBegin\nLightSource "point" "rgb I" [ 1 1 1 ]\n')
    with pytest.raises(SpectrumError, match="cannot be cut"):
        edit_scene(scene, None, tmp_path / "c" / "d.pbrt", cut_emitters=True)


def test_dark_emitters_get_scale_zero_and_the_others_keep_theirs(tmp_path: Path) -> None:
    """``dark`` names emitters by (file name, line), in the scene and in its Included files; those
    get "scale" 0 (replacing one they give), the rest are untouched."""
    src = tmp_path / "scene.pbrt"
    src.write_text((DATA / "several.pbrt").read_text().replace(
        'LightSource "spot"', 'LightSource "spot" "float scale" [ 3 ]').replace(
        '"sub/lights.pbrt"', f'"{DATA / "sub" / "lights.pbrt"}"'))
    out = edit_scene(src, None, tmp_path / "copy.pbrt", dark={("scene.pbrt", 17), ("scene.pbrt", 18),
                                                              ("lights.pbrt", 6)})
    text = out.read_text()
    assert 'LightSource "point" "float scale" [ 0 ] "rgb I" [ 1 1 1 ]' in text
    assert 'LightSource "spot" "float scale" [ 0 ]' in text and "[ 3 ]" not in text
    included = next(tmp_path.glob("include-1-*.pbrt")).read_text()
    assert 'LightSource "point" "float scale" [ 0 ] "spectrum I"' in included
    # the area lights and the distant light stay lit
    assert 'AreaLightSource "diffuse" "spectrum L" [ 400 0 450 10' in text
    assert 'AreaLightSource "diffuse" "spectrum L" [ 400 0 450 1 ' in included
    assert 'LightSource "distant"\n' in text
