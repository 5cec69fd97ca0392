"""The shipped Cornell box works once installed (docs/data.md: the folder ships on its own in
the wheel): its folder is self-contained, so the copy a wheel carries
(``wavelength_pdf/_data/cornell_box``) renders the checkout's pixels and gives the optimizer the
same lamp; ``published`` names ``--shared`` when the shared material is not where it looked."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from repo_paths import PBRT, REPO

SCENE_DIR = REPO / "scenes" / "cornell-box"
SPD = "tri-band-fluorescent.spd"
#: Quoted strings in a scene that name an input file.
INPUT = re.compile(r'"([^"\s]+\.(?:spd|ply|pbrt|obj|csv))"')


def _installed_copy(tmp_path: Path) -> Path:
    """The folder as a wheel installs it: mapped to ``wavelength_pdf/_data/cornell_box`` by
    pyproject.toml, nothing else of the checkout beside it."""
    dest = tmp_path / "site-packages" / "wavelength_pdf" / "_data" / "cornell_box"
    shutil.copytree(SCENE_DIR, dest, symlinks=False)
    return dest / "scene.pbrt"


def test_the_lamp_spectrum_beside_the_scene_is_the_projects():
    assert (SCENE_DIR / SPD).read_bytes() == (REPO / "spectra" / SPD).read_bytes(), \
        "scenes/cornell-box/tri-band-fluorescent.spd differs from spectra/'s: run scripts/make_cornell_box.py"


def test_every_file_the_scene_names_is_inside_its_folder():
    text = (SCENE_DIR / "scene.pbrt").read_text()
    named = INPUT.findall(text)
    assert SPD in named, named
    for name in named:
        assert not Path(name).is_absolute() and ".." not in Path(name).parts, \
            f"scenes/cornell-box/scene.pbrt names {name}, outside its folder: the installed copy cannot find it"
        assert (SCENE_DIR / name).is_file(), name


def test_the_installed_copy_gives_the_optimizer_the_same_lamp(tmp_path):
    from wavelength_pdf.spectra import load_spectra, load_spectrum

    (installed,) = load_spectra(str(_installed_copy(tmp_path)))
    (checkout,) = load_spectra(str(SCENE_DIR / "scene.pbrt"))
    lamp = load_spectrum(str(REPO / "spectra" / SPD))
    assert installed.name == checkout.name == lamp.name == "tri-band-fluorescent"
    for sp in (installed, checkout):
        np.testing.assert_array_equal(sp.wavelengths, lamp.wavelengths)
        np.testing.assert_array_equal(sp.values, lamp.values)


def _render(pbrt: Path, scene: Path, out: Path) -> np.ndarray:
    from wavelength_pdf.exr import read_rgb

    run = subprocess.run([str(pbrt), "--spp", "4", "--resolution", "24x24", "--seed", "3", "--nthreads", "1",
                          "--outfile", str(out), str(scene)], capture_output=True, text=True, timeout=300,
                         cwd=out.parent)
    assert run.returncode == 0, run.stderr[-2000:]
    return read_rgb(out)


def test_the_installed_copy_renders_the_checkouts_pixels(tmp_path, pbrt):
    """The installed copy, the checkout's scene and the scene as it was before (naming
    ../../spectra/tri-band-fluorescent.spd) render the same pixels, bit for bit."""
    before = tmp_path / "before" / "scene.pbrt"
    before.parent.mkdir()
    text = (SCENE_DIR / "scene.pbrt").read_text()
    assert f'"spectrum L" "{SPD}"' in text
    before.write_text(text.replace(f'"spectrum L" "{SPD}"', f'"spectrum L" "{REPO / "spectra" / SPD}"')
                      .replace('"meshes/', f'"{SCENE_DIR}/meshes/'))
    installed = _installed_copy(tmp_path)
    elsewhere = tmp_path / "work"
    elsewhere.mkdir()
    images = [_render(pbrt, scene, elsewhere / f"{i}.exr")
              for i, scene in enumerate((SCENE_DIR / "scene.pbrt", before, installed))]
    assert images[0].mean() > 0
    for other in images[1:]:
        np.testing.assert_array_equal(other, images[0])


def test_published_names_shared_when_the_material_is_missing(tmp_path):
    from wavelength_pdf.cli.evaluate import published_jobs

    with pytest.raises(FileNotFoundError) as missing:
        published_jobs(tmp_path / "nowhere")
    assert "--shared" in str(missing.value.strerror) and missing.value.filename == str(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError) as incomplete:
        published_jobs(tmp_path / "empty", ["cornell-box/2482"])
    assert "--shared" in str(incomplete.value.strerror)
    run = subprocess.run([sys.executable, "-m", "wavelength_pdf", "published", "--shared", str(tmp_path / "nowhere"),
                          "-o", str(tmp_path / "out"), "--pbrt", str(PBRT)], capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)
    assert run.returncode == 2 and "--shared DIR" in run.stderr and str(tmp_path / "nowhere") in run.stderr, run.stderr


def test_published_default_for_an_installed_package_is_the_current_folder(monkeypatch, tmp_path):
    from wavelength_pdf import data
    from wavelength_pdf.cli import evaluate as commands

    monkeypatch.setattr(data, "in_checkout", lambda: False)
    monkeypatch.chdir(tmp_path)
    assert commands.default_shared() == tmp_path / "shared"
    monkeypatch.setattr(data, "in_checkout", lambda: True)
    assert commands.default_shared() == REPO.parent / "shared"
