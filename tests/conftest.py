"""Shared fixtures: where the repository, the renderer and ../shared are.

``$WAVELENGTH_PDF_SHARED`` names the folder of shared reference material (scenes, LSPDD
spectra, reference tables); by default ``../shared`` beside the repository. Tests that need
it skip cleanly when it is absent.
"""
from __future__ import annotations

import os
from pathlib import Path

# The suite compiles the objective for hundreds of problem shapes, and on a clean machine
# (CI: an empty compilation cache) compiling is most of its time. XLA's backend optimization
# level 0 compiles them in about half the time and runs these small problems about as fast
# (tests/python/wavelength_pdf/test_objective_pixels.py from an empty cache: 347 s at the
# default level, 179 s at 0; 56 s either way with the cache warm); results change in
# rounding only, and no test depends on speed. Set before JAX creates its backend, and
# inherited by the commands and workers the tests start; a level the user set is kept.
if "xla_backend_optimization_level" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " --xla_backend_optimization_level=0").strip()

import jax  # noqa: E402
import pytest  # noqa: E402

from repo_paths import PBRT, REPO, SHARED  # noqa: E402,F401  (one place for the paths)

# The tests call the numerical modules (objective, sampling, health) directly, which expect
# float64; the library's entry points scope it themselves (tests/python/wavelength_pdf/test_package.py
# checks that importing the package leaves this setting alone, in a fresh interpreter).
jax.config.update("jax_enable_x64", True)


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def shared() -> Path:
    """The shared reference material, or a clean skip when it is absent."""
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} (shared reference material) is not present")
    return SHARED


@pytest.fixture(scope="session")
def pbrt() -> Path:
    """The renderer built by scripts/setup.sh (a missing build is a failure, not a skip)."""
    assert PBRT.is_file(), f"{PBRT} is missing: run bash scripts/setup.sh"
    return PBRT
