"""Shared fixtures: where the repository, the renderer and ../shared are."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
#: The renderer under test; PBRT_BIN overrides it (e.g. a developer's own build folder).
PBRT = Path(os.environ.get("PBRT_BIN", REPO / "build" / "pbrt"))


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def shared() -> Path:
    """../shared, or a clean skip when this checkout has none beside it."""
    if not SHARED.is_dir():
        pytest.skip("../shared is not present beside the repository")
    return SHARED


@pytest.fixture(scope="session")
def pbrt() -> Path:
    """The renderer built by scripts/setup.sh (a missing build is a failure, not a skip)."""
    assert PBRT.is_file(), f"{PBRT} is missing: run bash scripts/setup.sh"
    return PBRT
