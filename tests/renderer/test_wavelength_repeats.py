"""``pbrt --wavelength-repeats K`` (design §5.2): each camera sample traced K times with its
random numbers replayed and only the wavelength number shifted by k/K, averaged. The benchmark's
floor: the same expectation, with the wavelength noise averaged away. And the render statistics
every image records (``renderCPUSeconds``, ``meanPathDepth``, design §5.3)."""
from __future__ import annotations

import subprocess

import numpy as np
import pytest

from wavelength_pdf.exr import read_header, read_rgb

# A grey box lit by a lamp with one narrow line: with uniform wavelength sampling most paths miss
# the line, so wavelength noise dominates; every path scatters at least once.
SCENE = """
LookAt 0 0 -3  0 0 0  0 1 0
Camera "perspective" "float fov" [50]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16]
Sampler "independent"
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" [380 0 549 0 550 1 551 0 780 0] "float scale" [300]
  Translate 0 0.9 0
  Shape "sphere" "float radius" [0.3]
AttributeEnd
Material "diffuse" "rgb reflectance" [0.7 0.5 0.3]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 -1 -2  2 -1 -2  2 -1 2  -2 -1 2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 -1 2  2 -1 2  2 2 2  -2 2 2]
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    p = tmp_path_factory.mktemp("repeats") / "scene.pbrt"
    p.write_text(SCENE)
    return p


def render(pbrt, scene, out, *args, spp=16, seed=1):
    r = subprocess.run([str(pbrt), "--quiet", "--spp", str(spp), "--seed", str(seed), "--maxdepth", "2",
                        "--wavelength-sampling", "uniform", "--wavelength-range", "380", "780",
                        "--outfile", str(out), *args, str(scene)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return read_rgb(out), read_header(out)


def lit_mask(img):
    """Pixels not showing the lamp itself (its own pixels carry the line unattenuated)."""
    return img.sum(axis=-1) < 5 * np.median(img.sum(axis=-1))


def test_one_repeat_is_the_plain_render(pbrt, scene, tmp_path):
    a, ha = render(pbrt, scene, tmp_path / "a.exr")
    b, hb = render(pbrt, scene, tmp_path / "b.exr", "--wavelength-repeats", "1")
    np.testing.assert_array_equal(a, b)
    assert "wavelengthRepeats" not in ha and "wavelengthRepeats" not in hb


def test_repeats_keep_the_mean_and_remove_wavelength_noise(pbrt, scene, tmp_path):
    ref = render(pbrt, scene, tmp_path / "ref.exr", spp=2048, seed=9)[0]
    m = lit_mask(ref)
    ref = ref[m]
    plain = [render(pbrt, scene, tmp_path / f"p{s}.exr", seed=s)[0][m] for s in (1, 2)]
    rep = [render(pbrt, scene, tmp_path / f"r{s}.exr", "--wavelength-repeats", "32", seed=s) for s in (1, 2)]
    assert rep[0][1]["wavelengthRepeats"] == 32
    rep = [r[0][m] for r in rep]
    var_plain = np.mean((plain[0] - plain[1]) ** 2) / 2
    var_rep = np.mean((rep[0] - rep[1]) ** 2) / 2
    assert var_rep < var_plain / 5  # the noise here is mostly wavelength noise
    # Same expectation: the repeated image's mean matches a long plain render's.
    se = np.sqrt(np.sum((rep[0] - rep[1]) ** 2, axis=0) / 4) / rep[0].shape[0]
    se_ref = np.sqrt(var_plain * 16 / 2048 / ref.shape[0])
    diff = (rep[0] + rep[1]).mean(axis=0) / 2 - ref.mean(axis=0)
    assert np.all(np.abs(diff) < 5 * np.sqrt(se ** 2 + se_ref ** 2)), (diff, se, se_ref)


def test_statistics_in_the_header(pbrt, scene, tmp_path):
    _, h1 = render(pbrt, scene, tmp_path / "d1.exr", "--maxdepth", "1")
    _, h2 = render(pbrt, scene, tmp_path / "d2.exr")
    # Surface hits per camera path: with maxdepth 1, the first hit (every pixel here sees a
    # surface) and the hit that ends the path where its continuation does not escape, so
    # between 1 and 2; more with maxdepth 2 (at most 3).
    assert 1.0 <= h1["meanPathDepth"] <= 2.0
    assert h1["meanPathDepth"] < h2["meanPathDepth"] <= 3.0
    assert h2["renderCPUSeconds"] > 0


@pytest.mark.parametrize("value", ["0", "-3", "x", "70000"])
def test_bad_repeats_are_refused(pbrt, scene, tmp_path, value):
    out = tmp_path / "bad.exr"
    r = subprocess.run([str(pbrt), "--wavelength-repeats", value, "--outfile", str(out), str(scene)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and "--wavelength-repeats" in r.stderr
    assert not out.exists()
