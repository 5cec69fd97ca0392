"""Per-pixel colour error of a rendered image against a ground truth (design §6).

Linear RGB in the film's colour space -> XYZ (no transfer-function decoding: the EXR is
linear) -> CIELAB with the D65 white at Y = 1 -> CIEDE2000. All colorimetry is colour-science's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# colour-science is imported where it is used: importing it takes a second (it imports
# matplotlib), and the command line imports this module for every subcommand.


def _d65_xy() -> np.ndarray:
    """The white of the Lab conversion: D65 chromaticity, Y = 1 (design §6)."""
    import colour

    return colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]


def rgb_to_xyz(rgb: np.ndarray, colourspace: str = "sRGB") -> np.ndarray:
    """Linear RGB (..., 3) in a named colour space to CIE XYZ, without any decoding."""
    import colour

    cs = colour.RGB_COLOURSPACES[colourspace]
    return np.asarray(rgb, dtype=np.float64) @ np.asarray(cs.matrix_RGB_to_XYZ).T


def rgb_to_lab(rgb: np.ndarray, colourspace: str = "sRGB") -> np.ndarray:
    """Linear RGB (..., 3) to CIELAB with the D65 white at Y = 1."""
    import colour

    return colour.XYZ_to_Lab(rgb_to_xyz(rgb, colourspace), _d65_xy())


def delta_e_map(image: np.ndarray, truth: np.ndarray, colourspace: str = "sRGB") -> np.ndarray:
    """CIEDE2000 between two linear RGB images of the same shape, per pixel (h, w)."""
    if image.shape != truth.shape:
        raise ValueError(f"image shape {image.shape} differs from ground truth {truth.shape}")
    if not (np.all(np.isfinite(image)) and np.all(np.isfinite(truth))):
        raise ValueError("image has NaN or infinite pixels")
    import colour

    return np.asarray(colour.delta_E(rgb_to_lab(image, colourspace), rgb_to_lab(truth, colourspace),
                                     method="CIE 2000"))


@dataclass(frozen=True)
class ErrorStats:
    """Summary of a per-pixel error map: the mean (the figure Dobos 2025 reports), median, p95."""

    mean: float
    median: float
    p95: float

    @staticmethod
    def of(error_map: np.ndarray) -> "ErrorStats":
        e = np.asarray(error_map, dtype=np.float64).ravel()
        return ErrorStats(float(e.mean()), float(np.median(e)), float(np.percentile(e, 95)))
