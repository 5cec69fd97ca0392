"""Reading and writing the renderer's images: linear RGB, 32-bit float OpenEXR.

Uses the OpenEXR Python bindings (PyPI ``OpenEXR``, the ``evaluation`` extra), imported at the
first image read or written: the optimizer imports this module without them. The renderer
writes linear values in the film's colour space (design §5), so no transfer function is
applied or removed here.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from wavelength_pdf import extras


def _openexr():
    return extras.module("OpenEXR", "evaluation")


class ImageError(ValueError):
    """An image that cannot be read as linear RGB."""


def _channels(path: str | Path) -> dict[str, np.ndarray]:
    """Every channel of an EXR file by name (OpenEXR's grouping: "RGB" for R, G, B)."""
    path = Path(path)
    if not path.is_file():
        raise ImageError(f"{path}: no such image file")
    OpenEXR = _openexr()
    try:
        with OpenEXR.File(str(path)) as f:
            return {name: np.asarray(ch.pixels, dtype=np.float64) for name, ch in f.channels().items()}
    except Exception as e:  # OpenEXR raises plain exceptions for unreadable files
        raise ImageError(f"{path}: cannot read as OpenEXR: {e}") from e


def read_rgb(path: str | Path) -> np.ndarray:
    """Read an EXR file as a (height, width, 3) float64 array of linear RGB.

    Raises
    ------
    ImageError
        If the file is missing, not an EXR file, or has no R, G and B channels.
    """
    channels = _channels(path)
    if "RGB" in channels:
        return channels["RGB"]
    if all(c in channels for c in "RGB"):
        return np.stack([channels[c] for c in "RGB"], axis=-1)
    if "RGBA" in channels:
        return channels["RGBA"][..., :3]
    raise ImageError(f"{path}: no R, G, B channels (has {sorted(channels)})")


def read_spectral(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a spectral film's buckets (OpenEXR's spectral layout: channels ``S0.<nm>nm``, the
    decimal point written as a comma) as (centres in nm, increasing; a (height, width, B)
    float64 array of spectral radiance).

    Raises
    ------
    ImageError
        If the file is missing, not an EXR file, or has no spectral channel.
    """
    named = {float(name[3:-2].replace(",", ".")): ch for name, ch in _channels(path).items()
             if name.startswith("S0.") and name.endswith("nm")}
    if not named:
        raise ImageError(f"{path}: no spectral channels S0.<nm>nm (a \"spectral\" film writes them)")
    centres = np.array(sorted(named))
    return centres, np.stack([named[c] for c in centres], axis=-1)


def read_channel(path: str | Path, name: str) -> np.ndarray:
    """Read one named channel of an EXR file as a (height, width) float64 array (e.g. a
    spectral film's ``wavelengths.terminated``).

    Raises
    ------
    ImageError
        If the file is missing, not an EXR file, or has no such channel.
    """
    channels = _channels(path)
    if name not in channels:
        raise ImageError(f"{path}: no channel {name!r} (has {sorted(channels)[:8]}...)")
    return channels[name]


def read_header(path: str | Path) -> dict:
    """Read the header attributes of an EXR file, by name.

    Values are as the OpenEXR bindings give them: ``chromaticities`` is a tuple of eight
    floats (x, y of red, green, blue and white), ints and floats are Python numbers, strings
    are ``str`` and 2-vectors are numpy arrays. The renderer's attributes are listed in
    renderer/src/pbrt/render.h (``RenderMetadata``).

    Raises
    ------
    ImageError
        If the file is missing or not an EXR file.
    """
    path = Path(path)
    if not path.is_file():
        raise ImageError(f"{path}: no such image file")
    OpenEXR = _openexr()
    try:
        with OpenEXR.File(str(path), header_only=True) as f:
            return dict(f.header())
    except Exception as e:  # OpenEXR raises plain exceptions for unreadable files
        raise ImageError(f"{path}: cannot read as OpenEXR: {e}") from e


def write_rgb(path: str | Path, rgb: np.ndarray) -> None:
    """Write a (height, width, 3) array as a 32-bit float RGB EXR file."""
    rgb = np.ascontiguousarray(np.asarray(rgb, dtype=np.float32))
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ImageError(f"{path}: expected an (h, w, 3) array, got shape {rgb.shape}")
    OpenEXR = _openexr()
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": rgb}) as f:
        f.write(str(path))
