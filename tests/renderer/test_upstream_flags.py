"""pbrt-v4's command-line flags keep their meaning here: single-dash spellings, crop windows
(the EXR's data window inside the display window), --quick, --stats, the MSE against a
reference, partial images, logging; flags of features this renderer lacks are refused by
name, and the spectral film writes its buckets (design §5.1: the renderer takes pbrt-v4's
options)."""
from __future__ import annotations

import subprocess

import numpy as np
import OpenEXR
import pytest

from wavelength_pdf.exr import read_header, read_rgb

SCENE = """
LookAt 0 0.2 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [35]
Film "{film}" "integer xresolution" [24] "integer yresolution" [16] {filmparams}
Sampler "zsobol" "integer pixelsamples" [4]
WorldBegin
LightSource "distant" "point3 from" [1 2 -3] "point3 to" [0 0 0] "blackbody L" [3000]
LightSource "infinite" "rgb L" [0.1 0.2 0.3]
Material "diffuse" "rgb reflectance" [0.7 0.4 0.2]
Shape "sphere" "float radius" [1]
"""


def scene_file(tmp_path, film="rgb", filmparams=""):
    p = tmp_path / f"scene-{film}.pbrt"
    p.write_text(SCENE.format(film=film, filmparams=filmparams))
    return p


def run(pbrt, tmp_path, out, *args, scene=None, check=True):
    r = subprocess.run([str(pbrt), "--outfile", str(tmp_path / out), *args,
                        str(scene or scene_file(tmp_path))],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    if check:
        assert r.returncode == 0, r.stderr
    return r


def windows(path):
    with OpenEXR.File(str(path), header_only=True) as f:
        h = f.header()
        return tuple(int(v) for v in (*h["dataWindow"][0], *h["dataWindow"][1])), \
            tuple(int(v) for v in (*h["displayWindow"][0], *h["displayWindow"][1]))


def test_single_dash_spellings_mean_the_double_dash_ones(pbrt, tmp_path):
    run(pbrt, tmp_path, "a.exr", "--quiet", "--spp", "2", "--seed", "7")
    run(pbrt, tmp_path, "b.exr", "-quiet", "-spp", "2", "-seed=7")
    np.testing.assert_array_equal(read_rgb(tmp_path / "a.exr"), read_rgb(tmp_path / "b.exr"))


@pytest.mark.parametrize("args,bounds", [
    (("--cropwindow", "0.25,0.75,0.5,1"), (6, 18, 8, 16)),
    (("--pixelbounds", "3,11,2,9"), (3, 11, 2, 9)),
    (("-pixelbounds", "3,11,2,9"), (3, 11, 2, 9)),
    (("--pixel", "5,7"), (5, 6, 7, 8)),
])
def test_a_crop_is_that_part_of_the_full_image(pbrt, tmp_path, args, bounds):
    """A pixel's value depends only on the scene, the seed and the pixel (render.h), so the
    crop is exactly the full image's pixels there, and the EXR places it in the frame."""
    run(pbrt, tmp_path, "full.exr", "--quiet")
    full = read_rgb(tmp_path / "full.exr")
    run(pbrt, tmp_path, "crop.exr", "--quiet", *args)
    x0, x1, y0, y1 = bounds
    np.testing.assert_array_equal(read_rgb(tmp_path / "crop.exr"), full[y0:y1, x0:x1])
    data, display = windows(tmp_path / "crop.exr")
    assert data == (x0, y0, x1 - 1, y1 - 1)
    assert display == (0, 0, 23, 15)


def test_the_command_lines_crop_replaces_the_films(pbrt, tmp_path):
    scene = scene_file(tmp_path, filmparams='"float cropwindow" [0 0.5 0 0.5]')
    run(pbrt, tmp_path, "crop.exr", "--quiet", "--pixelbounds", "20,24,10,16", scene=scene)
    assert windows(tmp_path / "crop.exr")[0] == (20, 10, 23, 15)


@pytest.mark.parametrize("args,message", [
    (("--cropwindow", "0,1,0"), "expected 4 comma-separated values"),
    (("--pixelbounds", "4,4,0,3"), "the bounds are empty"),
    (("--pixel", "x,1"), "expected an integer"),
    (("--cropwindow", "0,1,0,1", "--pixel", "1,1"), "not both"),
    (("--mse-reference-out", "m.txt"), "needs --mse-reference-image"),
    (("--log-level", "loud"), "expected verbose, error or fatal"),
    (("--gpu",), "--gpu: not supported"),
    (("-interactive",), "--interactive: not supported"),
    (("--upgrade",), "use upstream pbrt-v4"),
])
def test_bad_or_unsupported_flags_stop_before_rendering(pbrt, tmp_path, args, message):
    r = run(pbrt, tmp_path, "x.exr", *args, check=False)
    assert r.returncode == 1
    assert message in r.stderr
    assert not (tmp_path / "x.exr").exists()


def test_flags_that_change_nothing_here_say_so(pbrt, tmp_path):
    r = run(pbrt, tmp_path, "a.exr", "--spp", "1", "--wavefront", "--render-coord-sys", "world")
    assert "--wavefront has no effect here" in r.stderr
    assert "--render-coord-sys has no effect here" in r.stderr


def test_quick_renders_a_quarter_of_the_resolution_at_one_sample(pbrt, tmp_path):
    run(pbrt, tmp_path, "q.exr", "--quiet", "--quick", "--spp", "16")
    assert read_rgb(tmp_path / "q.exr").shape == (4, 6, 3)
    assert read_header(tmp_path / "q.exr")["samplesPerPixel"] == 1


def test_mse_against_a_reference_and_per_pass(pbrt, tmp_path):
    run(pbrt, tmp_path, "ref.exr", "--quiet", "--spp", "64", "--seed", "1")
    r = run(pbrt, tmp_path, "img.exr", "--quiet", "--spp", "8", "--seed", "2",
            "--mse-reference-image", "ref.exr", "--mse-reference-out", "mse.txt")
    img, ref = read_rgb(tmp_path / "img.exr"), read_rgb(tmp_path / "ref.exr")
    mse = float(np.mean((img.astype(np.float64) - ref) ** 2))
    printed = float(r.stdout.split("MSE vs ref.exr:")[1].split()[0])
    assert printed == pytest.approx(mse, rel=1e-5)
    assert read_header(tmp_path / "img.exr")["MSE"] == pytest.approx(mse, rel=1e-5)
    lines = [line.split() for line in (tmp_path / "mse.txt").read_text().splitlines()]
    assert [int(spp) for spp, _ in lines] == [1, 2, 4, 8]
    assert float(lines[-1][1]) == pytest.approx(mse, rel=1e-5)
    # Passes do not change the image: a pixel's samples are added in the same order.
    run(pbrt, tmp_path, "plain.exr", "--quiet", "--spp", "8", "--seed", "2")
    np.testing.assert_array_equal(read_rgb(tmp_path / "plain.exr"), img)
    # A crop is compared with the full-frame reference where it lies.
    r = run(pbrt, tmp_path, "crop.exr", "--quiet", "--spp", "8", "--seed", "2",
            "--pixelbounds", "2,10,4,12", "--mse-reference-image", "ref.exr")
    crop_mse = float(np.mean((img[4:12, 2:10].astype(np.float64) - ref[4:12, 2:10]) ** 2))
    assert float(r.stdout.split("MSE vs ref.exr:")[1].split()[0]) == pytest.approx(crop_mse, rel=1e-5)
    # A reference of another size stops pbrt before rendering.
    run(pbrt, tmp_path, "small.exr", "--quiet", "--resolution", "8x8")
    r = run(pbrt, tmp_path, "y.exr", "--mse-reference-image", "small.exr", check=False)
    assert r.returncode == 1 and "the reference image is 8x8, the render 24x16" in r.stderr
    assert not (tmp_path / "y.exr").exists()


def test_partial_images_end_as_the_final_image(pbrt, tmp_path):
    r = run(pbrt, tmp_path, "p.exr", "--spp", "4", "--write-partial-images",
            "--log-level", "verbose")
    assert "wrote the partial image" in r.stderr and "at 2 spp" in r.stderr
    run(pbrt, tmp_path, "q.exr", "--quiet", "--spp", "4")
    np.testing.assert_array_equal(read_rgb(tmp_path / "p.exr"), read_rgb(tmp_path / "q.exr"))
    assert read_header(tmp_path / "p.exr")["samplesPerPixel"] == 4


def test_stats_and_logging(pbrt, tmp_path):
    r = run(pbrt, tmp_path, "s.exr", "--quiet", "--spp", "2", "--stats")
    assert "Statistics:" in r.stdout
    paths = int(r.stdout.split("Camera paths")[1].split()[0])
    assert paths == 24 * 16 * 2
    r = run(pbrt, tmp_path, "l.exr", "--quiet", "--spp", "1", "--log-file", "log.txt",
            "--log-utilization")
    log = (tmp_path / "log.txt").read_text()
    assert "loaded the scene: 2 lights" in log and "utilization:" in log
    # fatal: warnings are dropped (an ignored flag's warning here).
    r = run(pbrt, tmp_path, "f.exr", "--quiet", "--spp", "1", "--wavefront", "--log-level", "fatal")
    assert "warning" not in r.stderr


def test_exr_records_the_camera_matrices(pbrt, tmp_path):
    """worldToCamera and worldToNDC as pbrt-v4 writes them: the sphere's centre (world origin)
    lands at the frame point the camera looks at, the middle of the image."""
    run(pbrt, tmp_path, "m.exr", "--quiet", "--spp", "1")
    h = read_header(tmp_path / "m.exr")
    to_ndc = np.asarray(h["worldToNDC"], dtype=np.float64).reshape(4, 4)
    to_cam = np.asarray(h["worldToCamera"], dtype=np.float64).reshape(4, 4)
    p = to_ndc @ np.array([0, 0, 0, 1.0])  # the point looked at
    assert p[0] / p[3] == pytest.approx(0.5, abs=1e-4) and p[1] / p[3] == pytest.approx(0.5, abs=1e-4)
    eye = np.linalg.inv(to_cam) @ np.array([0, 0, 0, 1.0])
    np.testing.assert_allclose(eye[:3] / eye[3], [0, 0.2, -4], atol=1e-5)


def test_gbuffer_film_is_refused_at_its_line(pbrt, tmp_path):
    r = run(pbrt, tmp_path, "g.exr", scene=scene_file(tmp_path, film="gbuffer"), check=False)
    assert r.returncode == 1
    assert "scene-gbuffer.pbrt:4" in r.stderr and 'Film "gbuffer" is not supported' in r.stderr


def spectral_channels(path):
    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        names = [n for n in ch if n.startswith("S0.")]
        lam = np.array([float(n[3:-2].replace(",", ".")) for n in names])
        order = np.argsort(lam)
        return lam[order], np.stack([np.asarray(ch[names[i]].pixels, np.float64) for i in order], -1), \
            dict(f.header())


def test_spectral_film_writes_rgb_and_unbiased_buckets(pbrt, tmp_path):
    """The RGB is the rgb film's, to the bit; the buckets are the mean spectral radiance over
    each band whichever wavelength sampler drew them (visible and uniform agree within
    noise), and their luminance is the RGB's."""
    scene = scene_file(tmp_path, film="spectral",
                       filmparams='"integer nbuckets" [47] "float lambdamin" [360] "float lambdamax" [830]')
    args = ("--quiet", "--spp", "64", "--seed", "3")
    run(pbrt, tmp_path, "s.exr", *args, scene=scene)
    run(pbrt, tmp_path, "u.exr", *args, "--wavelength-sampling", "uniform", scene=scene)
    run(pbrt, tmp_path, "r.exr", *args)
    np.testing.assert_array_equal(read_rgb(tmp_path / "s.exr"), read_rgb(tmp_path / "r.exr"))
    lam, s, header = spectral_channels(tmp_path / "s.exr")
    _, u, _ = spectral_channels(tmp_path / "u.exr")
    assert header["spectralLayoutVersion"] == "1.0" and header["emissiveUnits"] == "W.m^-2.sr^-1"
    np.testing.assert_allclose(lam, 360 + 10 * (np.arange(47) + 0.5))
    mean_s, mean_u = s.mean(axis=(0, 1)), u.mean(axis=(0, 1))
    visible = (lam > 420) & (lam < 700)
    np.testing.assert_allclose(mean_s[visible], mean_u[visible], rtol=0.08)
    # Luminance: Y = sum_b bucket_b * integral of ybar over band b / CIE_Y_integral (the film
    # undid the lights' photometric scale); sRGB's Y row gives the RGB's.
    import colour
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    grid = np.arange(360, 831)
    ybar = np.interp(grid, cmfs.wavelengths, cmfs.values[:, 1], left=0, right=0)
    band = np.minimum(((grid - 360) // 10).astype(int), 46)
    ybar_band = np.bincount(band, weights=ybar, minlength=47)
    y_spec = (s.mean(axis=(0, 1)) * ybar_band).sum() / 106.856895
    rgb = read_rgb(tmp_path / "s.exr").astype(np.float64).mean(axis=(0, 1))
    y_rgb = rgb @ np.array([0.2126, 0.7152, 0.0722])
    assert y_spec == pytest.approx(y_rgb, rel=0.03)


@pytest.mark.parametrize("params,message", [
    ('"integer nbuckets" [0]', '"nbuckets" must lie in [1, 4096]'),
    ('"float lambdamin" [700] "float lambdamax" [400]', '"lambdamin" < "lambdamax"'),
])
def test_bad_spectral_film_parameters_name_the_line(pbrt, tmp_path, params, message):
    r = run(pbrt, tmp_path, "x.exr", scene=scene_file(tmp_path, "spectral", params), check=False)
    assert r.returncode == 1 and message in r.stderr and "scene-spectral.pbrt:4" in r.stderr
