"""The plugin works from an installed package, without the checkout: the project's wheel
(scripts/build_wheel.sh), installed into a fresh virtual environment, registers the texture and
renders a scene with a table written elsewhere, from a working directory outside the
repository."""
from __future__ import annotations

import subprocess
import zipfile

import pytest

from mitsuba_helpers import REPO, VECTORS
from wheel_helpers import build_wheel, clean_env, fresh_venv

pytestmark = pytest.mark.slow

SCRIPT = r"""
import sys, numpy as np
import wavelength_pdf, wavelength_pdf.mitsuba as wpm
import mitsuba as mi
assert wavelength_pdf.__file__.startswith(sys.argv[1]), wavelength_pdf.__file__
mi.set_variant("llvm_ad_spectral")
wpm.register("llvm_ad_spectral")
scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
    "sensor": {"type": "perspective", "srf": {"type": "wavelength_table", "filename": sys.argv[2]},
               "film": {"type": "hdrfilm", "width": 4, "height": 4}, "sampler": {"type": "independent", "sample_count": 8}},
    "light": {"type": "constant"}})
img = np.asarray(mi.render(scene))
assert np.all(np.isfinite(img)) and img.mean() > 0
print("ok", wavelength_pdf.__file__)
"""


def test_wheel_installed_elsewhere_renders(tmp_path):
    wheel = build_wheel(tmp_path / "wheels")
    names = zipfile.ZipFile(wheel).namelist()
    assert "wavelength_pdf/mitsuba/texture.py" in names and "wavelength_pdf/mitsuba/sampler.py" in names
    venv = tmp_path / "venv"
    bin_dir = fresh_venv(venv, wheel)
    table = tmp_path / "elsewhere" / "table.csv"
    table.parent.mkdir()
    table.write_text((VECTORS / "vectors-table.csv").read_text())
    work = tmp_path / "work"
    work.mkdir()
    out = subprocess.run([str(bin_dir / "python"), "-c", SCRIPT, str(venv), str(table)], cwd=work,
                         env=clean_env(bin_dir), capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.startswith("ok " + str(venv))


def test_plugin_reads_nothing_from_the_checkout():
    """No path into the repository (parents[...], REPO, the scenes) in the plugin's code."""
    for path in (REPO / "python" / "wavelength_pdf" / "mitsuba").glob("*.py"):
        text = path.read_text()
        for bad in ("parents[", "REPO", "scenes/", "tests/data", "__file__"):
            assert bad not in text, f"{path.name} refers to the checkout ({bad})"
