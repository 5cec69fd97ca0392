"""The renderer's command on bad input: a clear ``FILE:LINE: reason`` (or ``"PATH": reason``),
exit status 1, no output file, and the refusal comes before any rendering.

The scene-level cases (huge films, camera rays that overflow, shapes beyond range, directories
where files are expected) are unit tests in renderer/src/pbrt/robustness_test.cpp; these are
the cases the command line itself decides.
"""
from __future__ import annotations

import subprocess
import time
from pathlib import Path

import pytest
from input_files import sphere_scene

#: A scene that takes well over the time the checks below allow, were it rendered: an
#: error that comes "before rendering" must come in far less time than this scene takes.
SLOW_SCENE = sphere_scene(512, 4096)


def run(pbrt, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(pbrt), "--quiet", *args], capture_output=True, text=True, timeout=120)


@pytest.fixture
def slow_scene(tmp_path: Path) -> Path:
    p = tmp_path / "slow.pbrt"
    p.write_text(SLOW_SCENE)
    return p


def fails_fast(pbrt, *args: str) -> subprocess.CompletedProcess:
    t0 = time.monotonic()
    r = run(pbrt, *args)
    elapsed = time.monotonic() - t0
    assert r.returncode == 1, (r.returncode, r.stderr)
    # The slow scene needs minutes; the refusal must not wait for the render.
    assert elapsed < 20, f"the error came after {elapsed:.1f} s: {r.stderr}"
    assert r.stderr.startswith("pbrt: "), r.stderr
    assert "Rendering" not in r.stderr and "wrote" not in r.stderr, r.stderr
    return r


def test_resolution_scale_beyond_int_is_refused(pbrt, slow_scene, tmp_path):
    out = tmp_path / "x.exr"
    r = fails_fast(pbrt, "--resolution-scale", "1e9", "--outfile", str(out), str(slow_scene))
    assert f"{slow_scene}:1:1:" in r.stderr and "512x512 scaled by" in r.stderr, r.stderr
    assert not out.exists()


@pytest.mark.parametrize("name", ["x.jpg", "x.tiff", "x"])
def test_unsupported_outfile_extension_is_refused_before_rendering(pbrt, slow_scene, tmp_path, name):
    out = tmp_path / name
    r = fails_fast(pbrt, "--outfile", str(out), str(slow_scene))
    assert f'"{out}": unsupported output image format' in r.stderr, r.stderr
    assert not out.exists()


def test_outfile_that_is_a_directory_is_refused_before_rendering(pbrt, slow_scene, tmp_path):
    d = tmp_path / "already.exr"
    d.mkdir()
    r = fails_fast(pbrt, "--outfile", str(d), str(slow_scene))
    assert f'"{d}": is a directory' in r.stderr, r.stderr
    r = fails_fast(pbrt, "--outfile", str(tmp_path), str(slow_scene))
    assert "is a directory" in r.stderr, r.stderr


def test_outfile_in_a_missing_directory_is_refused(pbrt, slow_scene, tmp_path):
    out = tmp_path / "no" / "such" / "x.exr"
    r = fails_fast(pbrt, "--outfile", str(out), str(slow_scene))
    assert "the output directory does not exist" in r.stderr, r.stderr


def test_film_filename_is_checked_at_its_statement(pbrt, tmp_path):
    scene = tmp_path / "s.pbrt"
    scene.write_text('Film "rgb"\n    "string filename" "out.jpg"\n' + SLOW_SCENE.split("\n", 1)[1])
    r = subprocess.run([str(pbrt), "--quiet", str(scene)], capture_output=True, text=True,
                       timeout=120, cwd=tmp_path)
    assert r.returncode == 1, r.stderr
    assert f"{scene}:2:5:" in r.stderr and "unsupported output image format" in r.stderr, r.stderr
    assert not (tmp_path / "out.jpg").exists()


def test_directory_as_scene_is_named_as_such(pbrt, tmp_path):
    r = fails_fast(pbrt, "--outfile", str(tmp_path / "x.exr"), str(tmp_path))
    assert f'"{tmp_path}": is a directory, not a scene file' in r.stderr, r.stderr


def test_fifo_or_device_as_spectrum_or_include_is_refused_at_once(pbrt, tmp_path):
    """A FIFO named as a scene's .spd spectrum or Include held pbrt for ever, /dev/zero was
    read without end: regular files only (design §3.3, §5.5)."""
    import os

    os.mkfifo(tmp_path / "fifo.spd")
    (tmp_path / "zero.pbrt").symlink_to("/dev/zero")
    for line, kind in (('LightSource "infinite" "spectrum L" "fifo.spd"', "spectrum"),
                       ('Include "zero.pbrt"', "scene")):
        scene = tmp_path / "s.pbrt"
        scene.write_text(SLOW_SCENE + line + "\n")
        try:
            r = fails_fast(pbrt, "--outfile", str(tmp_path / "x.exr"), str(scene))
        except subprocess.TimeoutExpired:
            pytest.fail(f"pbrt still reading after 120 s: {line}")
        assert f"{scene}:6:" in r.stderr, r.stderr
        assert f"not a regular file (a device, FIFO or socket), not a {kind} file" in r.stderr, r.stderr
        assert not (tmp_path / "x.exr").exists()
