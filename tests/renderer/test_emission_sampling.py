"""``pbrt --wavelength-sampling emission`` (design §1.7, §5.2): the scene's own lamps, no table file.

(a) The table it samples is the Python construction: ``pbrt --emission-table`` equals
    ``wavelength-pdf baseline spd SCENE --whole-scene --range 360 830`` (and the luminance and
    xyz weights equal ``stratified_table`` of the same emission).
(b) Unbiased: images converge to pbrt-v4's visible sampling on the two-lamp box and on the six
    evaluation scenes (under their own emitters; skipped when ../shared is absent), with no
    coverage warning (the table is positive wherever a light emits).
(c) The same estimator as the Python-built table under ``--wavelength-pdf``: on the Cornell box
    under CFL 2482 (LSPDD) its per-pixel variance equals that table's within noise (and is far
    below visible sampling's), and with one seed the two images are the same.
(d) Bad cases stop pbrt before rendering with ``FILE:LINE:COL: reason`` and exit status 1: lights
    that emit nothing, a light whose power is not finite, a blackbody of 0 K, a non-finite
    spectrum; a scene without lights falls back to visible sampling with one line saying so.

Statistics as in test_wavelength_pdf.py: two renders with different seeds; E[(a - b)^2] = 2 var
per pixel gives the standard error of the image mean. Means agree when every channel is within
4 sigma, and each comparison must be able to see a DETECT bias of the luminance.
"""
from __future__ import annotations

import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from repo_paths import REPO, SHARED
from wavelength_pdf.cli import main
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.exr import read_rgb
from wavelength_pdf.table import read_table

TWO_LAMPS = REPO / "scenes" / "cornell-box-two-lamps" / "scene.pbrt"
CORNELL = REPO / "scenes" / "cornell-box" / "scene.pbrt"
CFL_2482 = SHARED / "spectra" / "lspdd" / "2482.csv"
SIX = ("cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase", "glass-of-water")
SIZE, MAXDEPTH = 16, 3
VISIBLE_SPP, EMISSION_SPP = 1024, 512   # doubled (twice at most) until DETECT is reached
DETECT = 0.04                           # the luminance bias every comparison must be able to see
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Y of linear sRGB


def run(pbrt: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(pbrt), *args], capture_output=True, text=True, timeout=600)


def coverage_warnings(stderr: str) -> list[str]:
    return [l for l in stderr.splitlines()
            if "sampling density is zero" in l or "outside the range of the" in l]


@dataclass
class Estimate:
    mean: np.ndarray   # per channel
    se: np.ndarray     # its standard error
    y_se: float        # standard error of the luminance mean
    stderr: str


def estimate(pbrt: Path, scene: Path, tmp: Path, args: tuple[str, ...], spp: int) -> Estimate:
    imgs, err = [], ""
    for seed in (1, 2):
        out = tmp / f"{args[-1]}-{spp}-{seed}.exr"
        r = run(pbrt, "--quiet", "--spp", str(spp), "--seed", str(seed), "--outfile", str(out), *args, str(scene))
        assert r.returncode == 0, r.stderr
        err += r.stderr
        imgs.append(read_rgb(out))
    a, b = imgs
    n = a.shape[0] * a.shape[1]
    d2 = (a - b) ** 2
    se = np.sqrt(d2.mean(axis=(0, 1)) / 2 / (2 * n))
    dy = (a - b) @ LUMINANCE
    return Estimate(0.5 * (a.mean(axis=(0, 1)) + b.mean(axis=(0, 1))), se,
                    float(np.sqrt((dy ** 2).mean() / 2 / (2 * n))), err)


def assert_converges_to_visible(pbrt: Path, scene: Path, tmp: Path, what: str) -> None:
    """Emission sampling's image mean equals visible sampling's within 4 sigma per channel,
    at enough spp that 4 sigma of the luminance is below DETECT of it."""
    for scale in (1, 2, 4):
        vis = estimate(pbrt, scene, tmp, ("--wavelength-sampling", "visible"), VISIBLE_SPP * scale)
        em = estimate(pbrt, scene, tmp, ("--wavelength-sampling", "emission"), EMISSION_SPP * scale)
        y = float(vis.mean @ LUMINANCE)
        y_sigma = np.hypot(vis.y_se, em.y_se)
        if 4 * y_sigma < DETECT * y:
            break
    assert 4 * y_sigma < DETECT * y, f"{what}: too noisy to see a {DETECT:.0%} bias ({y_sigma / y:.3%})"
    sigma = np.sqrt(vis.se ** 2 + em.se ** 2)
    z = (em.mean - vis.mean) / sigma
    print(f"{what}: emission vs visible z = {np.round(z, 2)} (luminance sigma {y_sigma / y:.2%})")
    assert np.all(np.abs(z) < 4), f"{what}: emission {em.mean} vs visible {vis.mean}: z = {z}"
    assert not coverage_warnings(em.stderr), em.stderr


# ---------------------------------------------------------------------------------------------
# (a) The table is the Python construction
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("weight", ["spd", "luminance", "xyz"])
def test_emission_table_is_the_python_construction(pbrt, tmp_path, weight):
    from wavelength_pdf import stratified
    from wavelength_pdf.scene_spectra import whole_scene_spectrum

    out = tmp_path / "emission.csv"
    r = run(pbrt, "--quiet", "--emission-table", str(out), "--emission-weight", weight, str(TWO_LAMPS))
    assert r.returncode == 0, r.stderr
    c = read_table(out)
    assert f"method: {weight}" in c.comments
    if weight == "spd":  # the documented command for renderers that only read tables
        py = tmp_path / "baseline.csv"
        assert main(["baseline", "spd", str(TWO_LAMPS), "--whole-scene", "--range", "360", "830",
                     "-o", str(py), "--pbrt", str(pbrt)]) == 0
        p = read_table(py)
    else:
        p = stratified.stratified_table(whole_scene_spectrum(TWO_LAMPS, 360.0, 830.0, pbrt), weight, 360.0, 830.0)
    assert (c.grid[0], c.grid[-1]) == (360.0, 830.0)
    np.testing.assert_allclose(c.grid, p.grid, rtol=1e-12, atol=0)
    np.testing.assert_allclose(c.pdfs, p.pdfs, rtol=0, atol=1e-12 * p.pdfs.max())


def test_emission_table_refuses_a_scene_without_emitters(pbrt, tmp_path):
    scene = tmp_path / "dark.pbrt"
    scene.write_text(HEADER + 'Shape "sphere"\n')
    out = tmp_path / "t.csv"
    r = run(pbrt, "--emission-table", str(out), str(scene))
    assert r.returncode == 1 and "no emitters" in r.stderr, r.stderr
    assert not out.exists()


# ---------------------------------------------------------------------------------------------
# (b) Unbiased
# ---------------------------------------------------------------------------------------------

def test_two_lamp_box_converges_to_visible_sampling(pbrt, tmp_path):
    scene = edit_scene(TWO_LAMPS, None, tmp_path / "scene.pbrt", resolution=(SIZE, SIZE), maxdepth=MAXDEPTH)
    assert_converges_to_visible(pbrt, scene, tmp_path, "two-lamp box")


@pytest.mark.parametrize("name", SIX)
def test_evaluation_scene_converges_to_visible_sampling(pbrt, tmp_path, name):
    path = SHARED / "scenes" / name / "scene-v4.pbrt"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    scene = edit_scene(path, None, tmp_path / "scene.pbrt", resolution=(SIZE, SIZE), maxdepth=MAXDEPTH)
    assert_converges_to_visible(pbrt, scene, tmp_path, name)


# ---------------------------------------------------------------------------------------------
# (c) The same estimator as the Python-built table, on the Cornell box under CFL 2482
# ---------------------------------------------------------------------------------------------

def render(pbrt: Path, scene: Path, tmp: Path, args: tuple[str, ...], seed: int) -> np.ndarray:
    exr = tmp / f"s{seed}.exr"
    r = run(pbrt, "--quiet", "--spp", "64", "--seed", str(seed), "--outfile", str(exr), *args, str(scene))
    assert r.returncode == 0 and not coverage_warnings(r.stderr), r.stderr
    return read_rgb(exr)


def pixel_variances(pbrt: Path, scene: Path, tmp: Path, args: tuple[str, ...], seeds: range) -> np.ndarray:
    """Per seed pair (independent renders): the mean over pixels of (a - b)^2 / 2, per channel,
    without the top quarter of the image (the lamp itself: bright edges, heavy tails)."""
    out = []
    for s in seeds[::2]:
        a, b = (render(pbrt, scene, tmp, args, seed) for seed in (s, s + 1))
        h = a.shape[0]
        out.append(((a[h // 4:] - b[h // 4:]) ** 2).mean(axis=(0, 1)) / 2)
    return np.array(out)


def test_same_error_as_the_python_table_on_the_cornell_box_under_cfl_2482(pbrt, tmp_path):
    if not CFL_2482.is_file():
        pytest.skip(f"{CFL_2482} is absent")
    from wavelength_pdf.spectra import load_spectrum

    lamp = load_spectrum(str(CFL_2482), lo=360.0, hi=830.0)
    scene = edit_scene(CORNELL, lamp, tmp_path / "scene.pbrt", lo=360.0, hi=830.0, resolution=(32, 32),
                       maxdepth=MAXDEPTH)
    table = tmp_path / "python.csv"
    assert main(["baseline", "spd", str(scene), "--whole-scene", "--range", "360", "830",
                 "-o", str(table), "--pbrt", str(pbrt)]) == 0
    emission = ("--wavelength-sampling", "emission")
    python = ("--wavelength-pdf", str(table))
    # One seed, one construction: the same wavelengths, the same image.
    np.testing.assert_array_equal(render(pbrt, scene, tmp_path, emission, 7),
                                  render(pbrt, scene, tmp_path, python, 7))
    # Independent seeds: the per-pixel variances agree within their noise over 8 pairs each.
    ve = pixel_variances(pbrt, scene, tmp_path, emission, range(1, 17))
    vt = pixel_variances(pbrt, scene, tmp_path, python, range(101, 117))
    ratio = ve.mean(axis=0) / vt.mean(axis=0)
    se_log = np.sqrt(ve.var(axis=0, ddof=1) / len(ve) / ve.mean(axis=0) ** 2
                     + vt.var(axis=0, ddof=1) / len(vt) / vt.mean(axis=0) ** 2)
    print(f"Cornell box, CFL 2482: pixel variance emission / Python table {np.round(ratio, 3)} "
          f"(se of the log {np.round(se_log, 3)})")
    assert np.all(4 * se_log < np.log(1.3)), f"too noisy to see a 30% difference: se(log ratio) {se_log}"
    assert np.all(np.abs(np.log(ratio)) < 4 * se_log), f"variance ratio emission/table {ratio} (se of log {se_log})"
    # ... and a difference of that size would show: visible sampling is far noisier here.
    vv = pixel_variances(pbrt, scene, tmp_path, ("--wavelength-sampling", "visible"), range(201, 209))
    print(f"  visible / emission {np.round(vv.mean(axis=0) / ve.mean(axis=0), 2)}")
    assert np.all(vv.mean(axis=0) > 2 * ve.mean(axis=0)), (vv.mean(axis=0), ve.mean(axis=0))


# ---------------------------------------------------------------------------------------------
# (d) Bad cases
# ---------------------------------------------------------------------------------------------

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [4] "integer yresolution" [4] "string filename" "out.exr"
WorldBegin
"""


@pytest.mark.parametrize("world, line, reason", [
    # every light emits nothing: the first one is named
    ('LightSource "point" "spectrum I" [400 1 700 1] "float scale" [0]\n'
     'AttributeBegin\nAreaLightSource "diffuse" "float scale" [0]\nShape "sphere"\nAttributeEnd\n',
     5, "no light of the scene emits between 360 and 830 nm"),
    # a light whose power overflows (a tiny luminance normalized to 1 nit, times a huge scale)
    ('LightSource "point" "spectrum I" [400 1e-30 700 1e-30] "float scale" [3e38]\n', 5,
     "emitted power is not finite"),
    ('AttributeBegin\nAreaLightSource "diffuse" "blackbody L" [0]\nShape "sphere"\nAttributeEnd\n', 6,
     "blackbody temperature must be positive"),
    ('LightSource "point" "spectrum I" [400 1 700 nan]\n', 5, "nan"),
])
def test_bad_lights_stop_pbrt_before_rendering(pbrt, tmp_path, world, line, reason):
    scene = tmp_path / "bad.pbrt"
    scene.write_text(HEADER + world)
    for args in (("--wavelength-sampling", "emission"), ("--emission-table", str(tmp_path / "t.csv"))):
        r = run(pbrt, "--spp", "1", *args, str(scene))
        assert r.returncode == 1, r.stderr
        assert f"{scene}:{line}:" in r.stderr and reason in r.stderr, r.stderr
        assert "Rendering" not in r.stderr
        assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.pbrt"]


def test_a_scene_without_lights_falls_back_to_visible_sampling(pbrt, tmp_path):
    from wavelength_pdf.exr import read_header

    scene = tmp_path / "dark.pbrt"
    scene.write_text(HEADER + 'Shape "sphere"\n')
    out = tmp_path / "dark.exr"
    r = run(pbrt, "--quiet", "--spp", "1", "--wavelength-sampling", "emission", "--outfile", str(out), str(scene))
    assert r.returncode == 0, r.stderr
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and "no lights" in lines[0] and "visible sampling instead" in lines[0], r.stderr
    assert read_header(out)["wavelengthSampler"] == "visible"


@pytest.mark.parametrize("args, message", [
    (("--wavelength-sampling", "emission", "--wavelength-range", "400", "700"), "--wavelength-range"),
    (("--emission-weight", "xyz"), "--emission-weight needs --wavelength-sampling emission"),
    (("--wavelength-sampling", "emission", "--emission-weight", "y"), "expected spd, luminance or xyz"),
    (("--wavelength-sampling", "emission", "--wavelength-pdf", "t.csv"), "give one or the other"),
])
def test_bad_options_are_usage_errors(pbrt, args, message):
    r = run(pbrt, *args, str(CORNELL))
    assert r.returncode == 1 and message in r.stderr, r.stderr


def test_help_says_which_to_use_when(pbrt):
    r = run(pbrt, "--help")
    assert r.returncode == 0
    for text in ("emission", "--emission-weight", "--emission-table", "spiky lamps", "optimized table"):
        assert text in r.stdout, text
