"""The package as a user installs it: the wheel that ``scripts/build_wheel.sh`` builds,
installed into a fresh virtual environment of its own, run from a folder outside the checkout.

Offline: the wheel is built with the setuptools of the running interpreter
(``--no-build-isolation``) and installed without its dependencies (``--no-deps``); the fresh
environment then sees the running environment's packages (NumPy, JAX, ...) through a ``.pth``
line placed after its own folder. Such a line only adds a folder to ``sys.path``: the ``.pth``
files inside that folder are not run, so the checkout's editable install stays switched off
and ``import wavelength_pdf`` finds the installed wheel.
"""
from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
from pathlib import Path

from repo_paths import REPO


def build_wheel(out: Path, *, checkout: Path = REPO, pbrt: Path | None = None) -> Path:
    """The wheel ``checkout``'s ``scripts/build_wheel.sh`` writes to ``out`` (with the renderer
    inside when ``pbrt`` is given)."""
    cmd = ["bash", str(checkout / "scripts" / "build_wheel.sh"), "--no-build-isolation", "--out", str(out)]
    if pbrt is not None:
        cmd += ["--with-pbrt", str(pbrt)]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=out.parent,
                         env={**os.environ, "PYTHON": sys.executable})
    assert run.returncode == 0, run.stderr[-3000:]
    wheel = Path(run.stdout.strip().splitlines()[-1])
    assert wheel.parent == out.resolve() and wheel.is_file(), run.stdout
    return wheel


def fresh_venv(where: Path, wheel: Path) -> Path:
    """A new virtual environment at ``where`` with ``wheel`` installed; returns its ``bin``."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(where)], check=True, timeout=120)
    python = where / "bin" / "python"
    # The running pip installs into the new interpreter's environment (pip --python), before
    # the dependency line below exists, so it sees (and could replace) nothing outside it.
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
                    "--no-index", "-q", str(wheel)], check=True, timeout=300)
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True, timeout=60).stdout.strip()
    ours = {sysconfig.get_paths()[k] for k in ("purelib", "platlib")}
    # "zz": after any .pth the wheel might bring, so the installed files come first.
    Path(site, "zz-test-dependencies.pth").write_text("".join(p + "\n" for p in sorted(ours)))
    return where / "bin"


def clean_env(bin_dir: Path) -> dict[str, str]:
    """The environment for a command of the fresh installation: its ``bin`` first on ``PATH``
    and nothing that points back into the checkout or at a renderer."""
    drop = {"PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "WAVELENGTH_PDF_PBRT", "PBRT_BIN"}
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env["PATH"] = os.pathsep.join([str(bin_dir), "/usr/bin", "/bin"])
    return env
