"""Helpers of the Mitsuba plugin's tests: variants, the cross-language vectors, paths."""
from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest

from repo_paths import REPO  # noqa: E402
VECTORS = REPO / "wavelength_table" / "tests" / "data"
SCENE = REPO / "scenes" / "cornell-box" / "scene.xml"
TRIBAND = REPO / "spectra" / "tri-band-fluorescent.spd"
TRIBAND_TABLE = REPO / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"

pytest.importorskip("mitsuba")
import wavelength_pdf.mitsuba as wpm  # noqa: E402  (sets DRJIT_LIBLLVM_PATH first)


def numbers(path: Path) -> np.ndarray:
    rows = [line for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]
    return np.array([[float(v) for v in r.split(",")] for r in rows[1:]])


@pytest.fixture(scope="session")
def vectors() -> np.ndarray:
    """Rows u, lambda0..3, mixture_pdf0..3 of the cross-language vectors."""
    return numbers(VECTORS / "vectors.csv")


@pytest.fixture(scope="session")
def vector_table() -> Path:
    return VECTORS / "vectors-table.csv"


def variant(name: str):
    """Set a variant, register the plugin in it; returns (mitsuba, the variant's module)."""
    import mitsuba as mi

    if name not in mi.variants():
        pytest.skip(f"this Mitsuba build has no {name}")
    try:
        mi.set_variant(name)
    except (ImportError, RuntimeError) as e:
        pytest.skip(f"{name} cannot start here: {e}")
    wpm.register(name)
    return mi, importlib.import_module(f"mitsuba.{name}")
