"""Files the project ships: its lamp spectra (``spectra/``) and its Cornell box
(``scenes/cornell-box/``).

In a checkout they are read where they are; an installed wheel carries them as package data
(``wavelength_pdf/_data/``, mapped from the same folders by ``pyproject.toml``, so nothing is
duplicated in the repository). The Cornell box is self-contained: its lamp's spectrum lies
beside ``scene.pbrt`` (a byte-for-byte copy of ``spectra/tri-band-fluorescent.spd``, which
``scripts/make_cornell_box.py`` writes), so the installed copy renders and optimizes as the
checkout's does.
"""
from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent
#: The repository root when running from a checkout (``python/wavelength_pdf/..``).
CHECKOUT = _HERE.parents[1]

#: Package-data folder -> folder of the checkout it is built from.
_FOLDERS = {"spectra": "spectra", "cornell-box": "scenes/cornell-box"}


def data_dir(name: str) -> Path:
    """The folder ``name`` ("spectra" or "cornell-box"): the wheel's copy, else the checkout's."""
    if name not in _FOLDERS:
        raise KeyError(f"no shipped data folder {name!r}; known: {', '.join(_FOLDERS)}")
    packaged = _HERE / "_data" / name.replace("-", "_")
    if packaged.is_dir():
        return packaged
    return CHECKOUT / _FOLDERS[name]


def in_checkout() -> bool:
    """True when the package runs from a source checkout (``build/`` and ``scenes/`` beside it)."""
    return (CHECKOUT / "pyproject.toml").is_file() and (CHECKOUT / "python").is_dir()


#: The demo's scene and spectrum.
def demo_scene() -> Path:
    return data_dir("cornell-box") / "scene.pbrt"


def demo_spectrum() -> Path:
    return data_dir("spectra") / "tri-band-fluorescent.spd"
