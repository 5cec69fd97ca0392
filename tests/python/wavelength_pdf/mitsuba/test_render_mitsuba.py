"""The Mitsuba render backend of the evaluation (``--renderer mitsuba``) and the Mitsuba
Cornell box: lamp scaling, scene checks, sampler variants, the generator, the CLI."""
from __future__ import annotations

import csv
import importlib.util
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from mitsuba_helpers import REPO, SCENE, TRIBAND, TRIBAND_TABLE
from wavelength_pdf.cli import main
from wavelength_pdf.evaluation import render_mitsuba as rm
from wavelength_pdf.evaluation.render import RenderError
from wavelength_pdf.spectra import load_spectrum, make_spectrum


def test_lamp_radiance_has_the_luminance_pbrt_gives_it():
    sp = load_spectrum(str(TRIBAND))
    lam, val = rm.lamp_radiance(sp, 16.0, 380.0, 780.0)
    assert lam[0] == 380.0 and lam[-1] == 780.0 and np.all(np.diff(lam) > 0)
    # Mitsuba shows Y = photometric(L) / its ybar integral: the lamp's Y is the luminance asked for
    assert rm.photometric(lam, val) / rm.MITSUBA_CIE_Y_INTEGRAL == pytest.approx(16.0, rel=1e-12)
    np.testing.assert_allclose(val / val.max(), sp(lam) / sp(lam).max(), rtol=1e-12)
    dark = make_spectrum("uv", "uv", [300.0, 350.0], [1.0, 1.0])
    with pytest.raises(Exception, match="no luminous energy"):
        rm.lamp_radiance(dark, 16.0)


def test_scene_checks_name_file_and_line(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<scene version="3.0.0">\n<sensor type="perspective">\n</scene>\n')
    with pytest.raises(RenderError, match=rf"{bad}:3: not well-formed"):
        rm.read_scene(bad)
    bare = tmp_path / "bare.xml"
    bare.write_text('<scene version="3.0.0"><sensor type="perspective"/></scene>\n')
    with pytest.raises(RenderError, match="missing lamp_wavelengths, lamp_values, lamp_luminance"):
        rm.read_scene(bare)
    with pytest.raises(FileNotFoundError):
        rm.read_scene(tmp_path / "missing.xml")


@pytest.mark.parametrize("method,srf", [("visible", None), ("uniform", "uniform"), ("table", "wavelength_table")])
def test_write_variant_puts_the_sampler_in_the_sensor(tmp_path, method, srf):
    out = rm.write_variant(SCENE, tmp_path / "s.xml", method, TRIBAND_TABLE, 380.0, 780.0, sampler="ldsampler")
    root = ET.parse(out).getroot()
    sensor = root.find("sensor")
    found = [c for c in sensor if c.get("name") == "srf"]
    assert [c.get("type") for c in found] == ([srf] if srf else [])
    if method == "uniform":
        assert {f.get("name"): float(f.get("value")) for f in found[0]} == {
            "value": 1.0, "wavelength_min": 380.0, "wavelength_max": 780.0}
    assert sensor.find("sampler").get("type") == "ldsampler"
    files = [e.get("value") for e in root.iter("string") if e.get("name") == "filename"]
    assert files and all(f.startswith("/") and (f.endswith(".csv") or (SCENE.parent / "meshes").as_posix() in f)
                         for f in files)


def test_generator_writes_the_committed_mitsuba_scene(tmp_path):
    spec = importlib.util.spec_from_file_location("make_cornell_box", REPO / "scripts" / "make_cornell_box.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    import sys

    argv, sys.argv = sys.argv, ["make_cornell_box.py", str(tmp_path / "scene.pbrt")]
    try:
        mod.main()
    finally:
        sys.argv = argv
    assert (tmp_path / "scene.pbrt").read_text() == (SCENE.parent / "scene.pbrt").read_text()
    assert (tmp_path / "scene.xml").read_text() == SCENE.read_text()
    for obj in (SCENE.parent / "meshes").glob("*.obj"):
        assert (tmp_path / "meshes" / obj.name).read_text() == obj.read_text()
    assert len(list((tmp_path / "meshes").glob("*.obj"))) == 8


def test_cli_evaluate_with_mitsuba(tmp_path, capsys):
    out = tmp_path / "ev"
    status = main(["evaluate", str(SCENE), str(TRIBAND), "-o", str(out), "--renderer", "mitsuba",
                   "--table", str(TRIBAND_TABLE), "--spp", "4", "--truth-spp", "32", "--resolution", "8x8"])
    assert status == 0
    rows = list(csv.DictReader(open(out / "results.csv")))
    assert [r["method"] for r in rows] == ["uniform", "visible", "table"]
    assert all(float(r["mean"]) > 0 and float(r["seconds"]) > 0 for r in rows)
    assert (out / "error-vs-spp-and-time.png").is_file()


def test_cli_bad_table_fails_before_rendering(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    shutil.copy(TRIBAND_TABLE, bad)
    lines = bad.read_text().splitlines()
    n = next(i for i, l in enumerate(lines) if l[:1].isdigit()) + 2
    lines[n] = lines[n].rsplit(",", 1)[0] + ",-1"
    bad.write_text("\n".join(lines) + "\n")
    status = main(["evaluate", str(SCENE), str(TRIBAND), "-o", str(tmp_path / "ev"), "--renderer", "mitsuba",
                   "--table", str(bad), "--spp", "4", "--truth-spp", "8", "--resolution", "8x8"])
    assert status != 0
    assert f"{bad}:{n + 1}: pdf3 is negative" in capsys.readouterr().err
    assert not (tmp_path / "ev" / "renders").exists()
