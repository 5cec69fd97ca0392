"""``pbrt --emission-spectrum OUT.spd SCENE`` (design §5.6): the scene's total emitted spectral
power, pbrt-v4's light power summed over its lights, against a hand computation; and its bad
input (a scene with no emitters: exit 1, no file)."""
from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np

#: Two quads (one two-sided, one scaled by a transform, one spectrum from a .spd file) and a
#: point light, every spectrum piecewise linear.
SCENE = """\
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [8] "integer yresolution" [8] "string filename" "never.exr"
WorldBegin
AttributeBegin
  Scale 2 1.5 1
  AreaLightSource "diffuse" "spectrum L" [300 1  450 4  700 2  900 3] "float scale" [3] "bool twosided" true
  Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  1 1 0  0 1 0] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
  Translate 0 0 -2
  AreaLightSource "diffuse" "spectrum L" "lamp.spd" "float scale" [0.5]
  Shape "trianglemesh" "point3 P" [0 0 0  0.5 0 0  0.5 4 0  0 4 0] "integer indices" [0 1 2 0 2 3]
AttributeEnd
LightSource "point" "spectrum I" [350 0  550 1  850 0] "float scale" [7] "point3 from" [0 2 0]
"""
LAMP_SPD = "350 0\n400 0\n589 10\n620 1\n850 1\n"


def run(pbrt, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(pbrt), "--quiet", *args], capture_output=True, text=True, timeout=60)


def luminance(x: list[float], y: list[float]) -> float:
    """pbrt-v4's 1-nit normalization: the sum of the spectrum times ybar at 360..830 nm."""
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    lam = np.arange(360, 831, dtype=np.float64)
    ybar = np.array([cmfs[float(v)][1] for v in lam])
    return float(np.sum(np.interp(lam, x, y) * ybar))


def read_spd(path: Path) -> np.ndarray:
    rows = [line.split() for line in path.read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    return np.array(rows, dtype=np.float64)


def test_emission_spectrum_matches_the_hand_computation(pbrt, tmp_path):
    (tmp_path / "scene.pbrt").write_text(SCENE)
    (tmp_path / "lamp.spd").write_text(LAMP_SPD)
    out = tmp_path / "out.spd"
    r = run(pbrt, "--emission-spectrum", str(out), str(tmp_path / "scene.pbrt"))
    assert r.returncode == 0, r.stderr
    data = read_spd(out)
    lam, phi = data[:, 0], data[:, 1]
    # The union of the emitters' nodes inside the sampled range 360..830 nm, ends included.
    assert list(lam) == [360, 400, 450, 550, 589, 620, 700, 830]
    a = ([300, 450, 700, 900], [1, 4, 2, 3])
    b = ([350, 400, 589, 620, 850], [0, 0, 10, 1, 1])
    p = ([350, 550, 850], [0, 1, 0])
    hand = (math.pi * (2 * 1.5) * 2 * 3 * np.interp(lam, *a) / luminance(*a)   # two-sided
            + math.pi * (0.5 * 4) * 0.5 * np.interp(lam, *b) / luminance(*b)   # one-sided
            + 4 * math.pi * 7 * np.interp(lam, *p) / luminance(*p))            # point light
    np.testing.assert_allclose(phi, hand, rtol=1e-6, atol=0)


def test_a_scene_without_emitters_is_an_error_and_writes_nothing(pbrt, tmp_path):
    scene = tmp_path / "dark.pbrt"
    scene.write_text(SCENE.split("AttributeBegin")[0] + 'Shape "sphere"\n')
    out = tmp_path / "out.spd"
    r = run(pbrt, "--emission-spectrum", str(out), str(scene))
    assert r.returncode == 1
    assert "no emitters" in r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == [scene]


def test_an_unwritable_output_is_refused_before_parsing(pbrt, tmp_path):
    r = run(pbrt, "--emission-spectrum", str(tmp_path / "no-dir" / "out.spd"),
            str(tmp_path / "missing.pbrt"))
    assert r.returncode == 1
    assert "output directory does not exist" in r.stderr


def test_help_lists_the_options(pbrt):
    r = subprocess.run([str(pbrt), "--help"], capture_output=True, text=True, timeout=60)
    assert "--emission-spectrum" in r.stdout and "--material-reflectances" in r.stdout


def test_material_reflectances_are_a_reflectance_file(pbrt, tmp_path):
    """The CSV reads back with the optimizer's reflectance reader (design §3.4): one column per
    distinct reflectance the shapes use; both queries at once write both files."""
    from wavelength_pdf.reflectances import read_reflectances

    (tmp_path / "scene.pbrt").write_text(SCENE + 'Material "diffuse" "rgb reflectance" [0.2 0.4 0.6]\n'
                                         'Shape "sphere"\n')
    (tmp_path / "lamp.spd").write_text(LAMP_SPD)
    refl, spd = tmp_path / "m.csv", tmp_path / "e.spd"
    r = run(pbrt, "--material-reflectances", str(refl), "--emission-spectrum", str(spd),
            str(tmp_path / "scene.pbrt"))
    assert r.returncode == 0, r.stderr
    s = read_reflectances(refl)
    line = SCENE.count("\n") + 1  # the Material statement follows the scene text
    assert s.labels == ("default material", f"{tmp_path / 'scene.pbrt'}:{line}:1")
    np.testing.assert_array_equal(s.wavelengths, np.arange(360.0, 831.0))
    np.testing.assert_allclose(s.values[0], 0.5)
    assert s.values[1][450 - 360] > 2 * s.values[1][650 - 360]  # rgb (0.2, 0.4, 0.6): bluish
    assert spd.is_file()
