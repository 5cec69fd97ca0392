"""Mitsuba-only users (design §8.3): the Mitsuba commands need no pbrt; an RGB variant and
a forgotten register() get errors that say so; an XML scene using the plugin renders from the
command line (``wavelength-pdf mitsuba``, ``python -m wavelength_pdf mitsuba``); the scalar
variants' cost is said once, with the alternative."""
from __future__ import annotations

import csv
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

from mitsuba_helpers import REPO, SCENE, TRIBAND, TRIBAND_TABLE, wpm  # noqa: F401

from wavelength_pdf.cli import main

#: A small scene whose sensor samples wavelengths from a table named relatively to it.
XML = """<scene version="3.0.0">
    <default name="spp" value="8"/>
    <integrator type="path"/>
    <sensor type="perspective">
        <texture type="wavelength_table" name="srf"><string name="filename" value="$table"/></texture>
        <film type="hdrfilm"><integer name="width" value="6"/><integer name="height" value="4"/></film>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    </sensor>
    <emitter type="constant"/>
    <shape type="sphere"><point name="center" x="0" y="0" z="4"/><bsdf type="diffuse"/></shape>
</scene>
"""


@pytest.fixture
def no_pbrt(monkeypatch):
    """Any lookup of pbrt fails the test."""
    from wavelength_pdf.cli import evaluate as commands
    from wavelength_pdf.evaluation import render

    def refuse(*a, **k):
        raise AssertionError("pbrt was looked up by a Mitsuba-only command")

    monkeypatch.setattr(commands, "find_pbrt", refuse)
    monkeypatch.setattr(render, "find_pbrt", refuse)
    monkeypatch.delenv("WAVELENGTH_PDF_PBRT", raising=False)


@pytest.mark.parametrize("command", ["evaluate", "demo"])
def test_mitsuba_commands_need_no_pbrt(no_pbrt, tmp_path, capsys, command):
    out = tmp_path / "ev"
    inputs = [str(SCENE), str(TRIBAND), "-o", str(out)] if command == "evaluate" else ["-o", str(out)]
    status = main([command, *inputs, "--renderer", "mitsuba", "--table", str(TRIBAND_TABLE),
                   "--spp", "2", "--truth-spp", "8", "--resolution", "6x6"])
    assert status == 0, capsys.readouterr().err
    rows = list(csv.DictReader(open(out / "results.csv")))
    assert [r["method"] for r in rows] == ["uniform", "visible", "table"]
    assert all(float(r["mean"]) >= 0 for r in rows)


def test_pbrt_options_with_mitsuba_are_refused(no_pbrt, tmp_path, capsys):
    assert main(["evaluate", str(SCENE), str(TRIBAND), "-o", str(tmp_path), "--renderer", "mitsuba",
                 "--pbrt", "/usr/bin/true"]) == 2
    assert "--pbrt is not used with --renderer mitsuba" in capsys.readouterr().err
    assert main(["evaluate", str(SCENE), "whole-scene", "-o", str(tmp_path), "--renderer", "mitsuba"]) == 2
    assert "need the pbrt renderer" in capsys.readouterr().err


def _scene_dict(table):
    return {"type": "scene",
            "sensor": {"type": "perspective", "srf": {"type": "wavelength_table", "filename": str(table)},
                       "film": {"type": "hdrfilm", "width": 2, "height": 2}},
            "light": {"type": "constant"}}


def test_rgb_variants_are_refused_with_the_reason():
    import mitsuba as mi

    before = mi.variant()
    try:
        with pytest.raises(wpm.PluginError, match="'llvm_ad_rgb' is not spectral.*llvm_ad_spectral"):
            wpm.load_dict(_scene_dict(TRIBAND_TABLE), variant="llvm_ad_rgb")
        # Plain Mitsuba in an RGB variant, after register(): the stand-in says why.
        mi.set_variant("scalar_rgb")
        wpm.register()
        with pytest.raises(RuntimeError, match="'scalar_rgb' is not spectral"):
            mi.load_dict(_scene_dict(TRIBAND_TABLE))
    finally:
        if before:
            mi.set_variant(before)


FRESH = r"""
import sys
import wavelength_pdf.mitsuba as wpm
import mitsuba as mi
mi.set_variant("scalar_spectral")
scene = {"type": "scene", "sensor": {"type": "perspective",
         "srf": {"type": "wavelength_table", "filename": sys.argv[1]},
         "film": {"type": "hdrfilm", "width": 2, "height": 2}}}
try:
    mi.load_dict(scene)                       # register() forgotten: Mitsuba's bare error...
except RuntimeError as e:
    print("EXPLAINED:", wpm.scenes._explained(e))
print("LOADED:", type(wpm.load_dict(scene)).__name__)   # ...the helper registers it itself
"""


def test_a_forgotten_register_is_explained_and_the_helpers_register():
    run = subprocess.run([sys.executable, "-c", FRESH, str(TRIBAND_TABLE)], capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert 'Plugin "wavelength_table" not found' in run.stdout
    assert "call wavelength_pdf.mitsuba.register() after mi.set_variant()" in run.stdout
    assert "LOADED: Scene" in run.stdout


def test_an_xml_scene_renders_from_the_command_line(tmp_path):
    import mitsuba as mi

    scene = tmp_path / "scene.xml"
    scene.write_text(XML)
    (tmp_path / "t.csv").write_text(TRIBAND_TABLE.read_text())
    work = tmp_path / "work"
    work.mkdir()
    run = subprocess.run([sys.executable, "-m", "wavelength_pdf", "mitsuba", str(scene), "-D", "table=t.csv",
                          "-D", "spp=4", "--seed", "5"], capture_output=True, text=True, timeout=600, cwd=work,
                         env={**os.environ, "PYTHONPATH": str(REPO / "python")})
    assert run.returncode == 0, run.stderr[-3000:]
    out = tmp_path / "scene.exr"  # beside the scene, as Mitsuba writes it
    assert f"wrote {out}" in run.stdout
    got = np.asarray(mi.Bitmap(str(out)))
    # The same scene through the library, same variant, spp and seed: the same pixels.
    mi.set_variant("llvm_ad_spectral")
    wpm.register()
    wpm.scenes._resolver(mi).prepend(str(tmp_path))
    want = np.asarray(mi.render(mi.load_file(str(scene), table="t.csv", spp="4"), seed=5))
    assert got.shape[:2] == (4, 6) and np.all(np.isfinite(got)) and got[..., :3].mean() > 0
    np.testing.assert_allclose(got[..., :3], want[..., :3], rtol=1e-6, atol=1e-7)


def test_the_command_line_names_a_bad_variant_and_a_missing_scene(tmp_path, capsys):
    scene = tmp_path / "scene.xml"
    scene.write_text(XML)
    assert main(["mitsuba", str(scene), "-m", "scalar_rgb", "-D", f"table={TRIBAND_TABLE}"]) == 2
    assert "'scalar_rgb' is not spectral" in capsys.readouterr().err
    assert main(["mitsuba", str(tmp_path / "none.xml")]) == 2
    assert "none.xml: no such scene file" in capsys.readouterr().err


def test_the_scalar_variants_cost_is_said_once_with_the_alternative():
    from wavelength_pdf.mitsuba import texture

    import mitsuba as mi

    before = mi.variant()
    texture._warned_scalar = False
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            wpm.load_dict(_scene_dict(TRIBAND_TABLE), variant="scalar_spectral")
            wpm.load_dict(_scene_dict(TRIBAND_TABLE), variant="scalar_spectral")
        said = [str(w.message) for w in caught if "scalar variant" in str(w.message)]
        assert len(said) == 1 and "5-7 times" in said[0] and "llvm_ad_spectral" in said[0]
    finally:
        if before:
            mi.set_variant(before)
