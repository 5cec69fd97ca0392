"""The package as a library: JAX's settings untouched, float64 results, the top-level API,
``python -m wavelength_pdf``, the shipped data and the renderer lookup."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from wavelength_pdf import data
from wavelength_pdf import renderer

from repo_paths import REPO  # noqa: E402

_PROBE = r"""
import jax
before = {k: getattr(jax.config, k) for k in ("jax_enable_x64", "jax_default_matmul_precision")}
import wavelength_pdf
from wavelength_pdf import optimize_spectrum, read_table, write_table, evaluate_table, Result
from wavelength_pdf import cli, optimize, objective, solvers, health, plots  # every module
after = {k: getattr(jax.config, k) for k in before}
assert before == after, (before, after)
assert jax.numpy.ones(2).dtype == jax.numpy.float32, "x64 switched on globally"
import numpy as np
from wavelength_pdf.spectra import Spectrum
wl = np.arange(380.0, 781.0, 10.0)
sp = Spectrum("flat", "test:flat", wl, np.ones(wl.size))
r = optimize_spectrum(sp, grid=np.linspace(380.0, 780.0, 21), solver_options={"max_evals": 20})
assert r.table.pdfs.dtype == np.float64 and isinstance(r.J, float)
ev = evaluate_table(sp, r.table)
assert abs(ev.J - r.J) <= 1e-12 * r.J, (ev.J, r.J)
assert jax.config.jax_enable_x64 is False and jax.numpy.ones(2).dtype == jax.numpy.float32
print("ok", r.J)
"""


def test_import_leaves_jax_config_and_results_are_float64():
    """In a fresh interpreter (the suite itself turns x64 on): import changes nothing in
    jax.config; the optimizer still computes in float64 and reproduces its J."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_ENABLE_X64"}
    proc = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                          env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.startswith("ok")


def test_python_dash_m_runs_the_command():
    proc = subprocess.run([sys.executable, "-m", "wavelength_pdf", "--version"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.startswith("wavelength-pdf ")


def test_shipped_data_is_found():
    assert data.demo_scene().is_file() and data.demo_spectrum().is_file()
    with pytest.raises(KeyError):
        data.data_dir("lspdd")


def _exe(path: Path) -> Path:
    path.write_text("#!/bin/sh\nexit 0\n")
    path.chmod(0o755)
    return path


def test_renderer_lookup_order(tmp_path, monkeypatch):
    """--pbrt, then $WAVELENGTH_PDF_PBRT, then the checkout's build/pbrt, then the wheel's
    own (_bin/pbrt), then PATH."""
    a, b, c = (_exe(tmp_path / n) for n in ("a", "b", "pbrt"))
    (tmp_path / "_bin").mkdir()
    bundled = _exe(tmp_path / "_bin" / "pbrt")
    (tmp_path / "bin").mkdir()
    on_path = _exe(tmp_path / "bin" / "pbrt")
    monkeypatch.setenv("PATH", str(tmp_path / "bin"))
    monkeypatch.setattr(renderer, "BUNDLED_PBRT", bundled)
    monkeypatch.setenv(renderer.PBRT_ENV, str(b))
    assert renderer.find_pbrt(a) == a
    assert renderer.find_pbrt() == b
    monkeypatch.delenv(renderer.PBRT_ENV)
    monkeypatch.setattr(renderer, "CHECKOUT_PBRT", c)
    assert renderer.find_pbrt() == c
    monkeypatch.setattr(renderer, "CHECKOUT_PBRT", tmp_path / "missing")
    assert renderer.find_pbrt() == bundled
    monkeypatch.setattr(renderer, "BUNDLED_PBRT", tmp_path / "_bin" / "missing")
    assert renderer.find_pbrt() == on_path


def test_the_bundled_renderer_is_inside_the_package():
    import wavelength_pdf

    assert renderer.BUNDLED_PBRT == Path(wavelength_pdf.__file__).resolve().parent / "_bin" / "pbrt"


def test_renderer_not_found_lists_where_it_looked_and_how_to_get_one(tmp_path, monkeypatch):
    monkeypatch.setenv(renderer.PBRT_ENV, str(tmp_path / "nope"))
    monkeypatch.setattr(renderer, "CHECKOUT_PBRT", tmp_path / "build" / "pbrt")
    monkeypatch.setattr(renderer, "BUNDLED_PBRT", tmp_path / "_bin" / "pbrt")
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(renderer.RendererNotFound) as e:
        renderer.find_pbrt()
    msg = str(e.value)
    for place in ("nope", "build/pbrt", "_bin/pbrt"):
        assert str(tmp_path / place) in msg, place
    assert "PATH" in msg and "--pbrt" in msg
    for way in ("scripts/setup.sh", "cmake --install", "build_wheel.sh --with-pbrt"):
        assert way in msg, way
    with pytest.raises(renderer.RendererNotFound, match="not an executable"):
        renderer.find_pbrt(tmp_path / "nope")


def test_ipopt_without_cyipopt_says_how_to_install(monkeypatch):
    import importlib.util

    from wavelength_pdf import optimize
    from wavelength_pdf.spectra import load_spectrum

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "cyipopt" else real(name, *a))
    with pytest.raises(ValueError, match=r"pip install cyipopt"):
        optimize.optimize_spectrum(load_spectrum("cie:D65"), solver="ipopt")


def test_every_subpackage_is_in_the_wheel(repo):
    """pyproject.toml lists the packages by hand (the data folders are mapped into the
    package): a subpackage missing from the list would be missing from an installed wheel."""
    import tomllib

    listed = set(tomllib.loads((repo / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    root = repo / "python"
    found = {".".join(p.parent.relative_to(root).parts) for p in root.rglob("__init__.py")}
    assert found <= listed, f"not in pyproject.toml's packages: {sorted(found - listed)}"
