"""Emitter spectra of pbrt-v4 scenes (design §3): one per distinct emitter, every documented form."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf.scene_spectra import (
    NotOptimizableWarning,
    scan_scene,
    scene_spectra,
    tokenize,
)
from wavelength_pdf.spectra import SpectrumError, load_spectra, load_spectrum, read_spd

from repo_paths import REPO  # noqa: E402
SCENES = REPO / "tests" / "data" / "scenes"
SPECTRA = REPO / "tests" / "data" / "spectra"
from repo_paths import SHARED  # noqa: E402

SHARED_SCENES = SHARED / "scenes"


def _spectra(name: str):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no emitter skipped unless a test says so
        return scene_spectra(SCENES / name)


# --- tokens --------------------------------------------------------------------------

def test_tokenizer_strings_comments_brackets_lines():
    text = 'Shape "sphere" # a comment "not a string"\n  "float radius" [ 1.5e0\n -2 ]\n"a\\"b"'
    toks = tokenize(text, Path("x.pbrt"))
    assert [(t.kind, t.text, t.line) for t in toks] == [
        ("word", "Shape", 1), ("str", "sphere", 1), ("str", "float radius", 2),
        ("[", "[", 2), ("num", "1.5e0", 2), ("num", "-2", 3), ("]", "]", 3), ("str", 'a"b', 4),
    ]


def test_unterminated_string():
    with pytest.raises(SpectrumError, match=r"x.pbrt:2: unterminated string"):
        tokenize('WorldBegin\nLightSource "point\n', Path("x.pbrt"))


# --- every documented form of an emitter spectrum ------------------------------------

def test_inline_spectrum():
    (sp,) = _spectra("inline.pbrt")
    np.testing.assert_array_equal(sp.wavelengths, [400, 450, 500, 600, 700])
    np.testing.assert_array_equal(sp.values, [0.0, 1.0, 0.5, 2.0, 0.0])
    assert sp.source == f"{SCENES / 'inline.pbrt'}:8", "file:line of the parameter"


def test_spectrum_from_file_relative_to_scene():
    (sp,) = _spectra("file.pbrt")
    ref = read_spd(SPECTRA / "tiny.spd")
    np.testing.assert_array_equal(sp.wavelengths, ref.wavelengths)
    np.testing.assert_array_equal(sp.values, ref.values)


def test_named_spectrum_is_colour_science_illuminant():
    (sp,) = _spectra("named.pbrt")
    ref = load_spectrum("cie:FL11")
    assert sp.name == "stdillum-F11"
    np.testing.assert_array_equal(sp.wavelengths, ref.wavelengths)
    np.testing.assert_array_equal(sp.values, ref.values)


def test_blackbody_follows_planck():
    (sp,) = _spectra("blackbody.pbrt")
    T = 3000.0
    h, c, k = 6.62607015e-34, 299792458.0, 1.380649e-23  # SI 2019 exact constants
    lam = sp.wavelengths * 1e-9
    planck = 1.0 / (lam**5 * np.expm1(h * c / (lam * k * T)))
    ratio = sp.values / planck
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-6)
    assert sp.values.max() == pytest.approx(1.0, rel=1e-12), "normalized to peak 1 as pbrt-v4"
    # Wien's displacement law: peak at b / T, b = 2.897771955e-3 m K.
    assert abs(sp.wavelengths[np.argmax(sp.values)] - 2.897771955e6 / T) <= 1.0


def test_missing_L_means_colour_space_illuminant():
    (sp,) = _spectra("default-illuminant.pbrt")
    np.testing.assert_array_equal(sp.values, load_spectrum("cie:D65").values)


def test_rgb_only_scene_is_not_optimizable():
    with pytest.raises(SpectrumError) as e:
        scene_spectra(SCENES / "rgb.pbrt")
    msg = str(e.value)
    assert msg.startswith(f"{SCENES / 'rgb.pbrt'}:3: ") and "RGB" in msg and "not" in msg, msg


# --- a scene with several emitters ---------------------------------------------------

def test_several_emitters_distinct_and_in_order():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sps = scene_spectra(SCENES / "several.pbrt")
    names = [s.name for s in sps]
    # Included inline spectrum (and its 10x brighter duplicate merged), the .spd named in the
    # included file, the blackbody from an Attribute "light" default, then stdillum-F2.
    assert names == ["several-line3", "tiny", "blackbody-5000K", "stdillum-F2"], names
    assert sps[0].source == f"{SCENES / 'sub' / 'lights.pbrt'}:3"
    np.testing.assert_array_equal(sps[1].values, read_spd(SPECTRA / "tiny.spd").values)
    # The shape-less area light (stdillum-A) emits nothing; the RGB light is reported.
    assert not any("stdillum-A" == n for n in names)
    msgs = [str(w.message) for w in caught if issubclass(w.category, NotOptimizableWarning)]
    assert len(msgs) == 1 and msgs[0].startswith(f"{SCENES / 'several.pbrt'}:17: "), msgs


def test_scan_lists_every_used_emitter_statement():
    ems = scan_scene(SCENES / "several.pbrt")
    where = [re.sub(r".*/", "", e.where) for e in ems]
    assert where == ["lights.pbrt:3", "lights.pbrt:6", "several.pbrt:6", "several.pbrt:15",
                     "several.pbrt:17", "several.pbrt:18"], where
    assert [e.spectrum is None for e in ems] == [False, False, False, False, True, False]


def test_load_spectrum_needs_a_choice_for_several_emitters():
    scene = str(SCENES / "several.pbrt")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotOptimizableWarning)
        with pytest.raises(SpectrumError, match=r"4 distinct emitter spectra.*#0: several-line3.*#3: stdillum-F2"):
            load_spectrum(scene)
        assert load_spectrum(scene + "#2").name == "blackbody-5000K"
        assert load_spectrum(scene + "#stdillum-F2").name == "stdillum-F2"
        with pytest.raises(SpectrumError, match="no emitter '7'"):
            load_spectrum(scene + "#7")
        assert len(load_spectra(scene)) == 4


# --- malformed scenes ----------------------------------------------------------------

@pytest.mark.parametrize(
    "name, line, reason",
    [
        ("bad-missing-include.pbrt", 2, "no such file"),
        ("bad-inline-nan.pbrt", 4, "cannot parse number 'nan'"),
        ("bad-unclosed.pbrt", 2, "'[' is never closed"),
    ],
)
def test_malformed_scene_files(name, line, reason):
    path = SCENES / name
    with pytest.raises(SpectrumError) as e:
        load_spectra(str(path))
    msg = str(e.value)
    assert msg.startswith(f"{path}:{line}: ") and reason in msg, msg


@pytest.mark.parametrize(
    "body, line, reason",
    [
        ('LightSource "point" "spectrum I" [ 400 1 500 ]', 2, "pairs"),
        ('LightSource "point" "spectrum I" [ 400 1 500 -1 ]', 2, "negative value"),
        ('LightSource "point" "spectrum I" [ 500 1 400 1 ]', 2, "strictly increasing"),
        ('LightSource "point" "spectrum I" [ 900 1 950 1 ]', 2, "no energy inside"),
        ('LightSource "point" "spectrum I" "stdillum-Z9"', 2, "neither a named spectrum nor a file"),
        ('LightSource "point" "blackbody I" [ -5 ]', 2, "temperature must be positive"),
        ('LightSource "point" "float I" [ 1 ]', 2, "must be spectrum, blackbody or rgb"),
        ('LightSource "point" "spectrum I" "missing.spd"', 2, "missing.spd"),
        ('AttributeEnd', 2, "AttributeEnd without AttributeBegin"),
        ('LightSource "point" ]', 2, "']' without '['"),
    ],
)
def test_malformed_scene_variants(tmp_path, body, line, reason):
    path = tmp_path / "s.pbrt"
    path.write_text("WorldBegin\n" + body + "\n")
    with pytest.raises(SpectrumError) as e:
        load_spectra(str(path))
    msg = str(e.value)
    assert msg.startswith(f"{path}:{line}: ") and reason in msg, msg


def test_missing_scene_and_empty_scene(tmp_path):
    with pytest.raises(SpectrumError, match="no such file"):
        load_spectra(str(tmp_path / "none.pbrt"))
    (tmp_path / "empty.pbrt").write_text("WorldBegin\nShape \"sphere\"\n")
    with pytest.raises(SpectrumError, match="no emitters"):
        load_spectra(str(tmp_path / "empty.pbrt"))


def test_include_cycle_is_an_error_not_a_hang(tmp_path):
    (tmp_path / "a.pbrt").write_text('Include "b.pbrt"\n')
    (tmp_path / "b.pbrt").write_text('Include "a.pbrt"\n')
    with pytest.raises(SpectrumError, match="nesting deeper"):
        load_spectra(str(tmp_path / "a.pbrt"))


# --- the evaluation scenes -----------------------------------------------------------

@pytest.mark.shared
@pytest.mark.skipif(not SHARED_SCENES.is_dir(), reason="../shared/scenes is not present")
@pytest.mark.parametrize("scene", ["cornell-box", "glass-of-water", "staircase", "teapot",
                                   "veach-bidir", "veach-mis"])
def test_evaluation_scenes_have_one_lamp_each(scene):
    path = SHARED_SCENES / scene / "scene-v4.pbrt"
    sps = _spectra_of(path)
    assert len(sps) == 1, [s.name for s in sps]
    # The spectrum is the inline array, as written (at its own resolution).
    text = path.read_text()
    line = int(sps[0].source.rsplit(":", 1)[1])
    array = text.splitlines()[line - 1].split("[", 1)[1].split("]", 1)[0].split()
    nums = np.array([float(v) for v in array])
    np.testing.assert_array_equal(sps[0].wavelengths, nums[0::2])
    np.testing.assert_array_equal(sps[0].values, nums[1::2])


def _spectra_of(path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return scene_spectra(path)


def test_other_statements_need_not_be_understood(tmp_path):
    """Names with spaces and unusual statements elsewhere do not disturb the emitters."""
    path = tmp_path / "s.pbrt"
    path.write_text('MakeNamedMaterial "Glass Bottle" "string type" "dielectric"\n'
                    'Texture "checks" "spectrum" "checkerboard" "float uscale" [ 4 ]\n'
                    'NamedMaterial "Glass Bottle"\n'
                    'Shape "bilinearmesh" "bool emissive" true\n'
                    'LightSource "point" "spectrum I" "stdillum-A"\n')
    (sp,) = _spectra_of(path)
    assert sp.name == "stdillum-A"


def test_emitter_needs_its_type(tmp_path):
    path = tmp_path / "s.pbrt"
    path.write_text('WorldBegin\nLightSource "spectrum I" [ 400 1 500 1 ]\n')
    with pytest.raises(SpectrumError, match=r"s.pbrt:2: expected a parameter"):
        load_spectra(str(path))
    path.write_text('WorldBegin\nLightSource [ 400 1 500 1 ]\n')
    with pytest.raises(SpectrumError, match=r"s.pbrt:2: LightSource needs a quoted type"):
        load_spectra(str(path))


def test_scene_or_include_that_is_a_fifo_or_device_is_refused(tmp_path):
    """Regular files only, as the renderer reads scenes (design §5.5): a FIFO named as a scene
    or an Include blocked for ever, /dev/zero was read without end."""
    from input_files import link_to_dev_zero, make_fifo, read_bounded

    fifo = make_fifo(tmp_path, "fifo.pbrt")
    zero = link_to_dev_zero(tmp_path, "zero.pbrt")
    including = tmp_path / "including.pbrt"
    including.write_text('WorldBegin\nInclude "zero.pbrt"\n')
    for path, where in ((fifo, f"{fifo}: {fifo}"), (zero, f"{zero}: {zero}"),
                        (including, f"{including}:2: {zero}")):
        status, out = read_bounded("wavelength_pdf.scene_spectra:scan_scene", path)
        assert status == 3, out
        assert out.startswith(f"SpectrumError: {where}: not a regular file"), out
