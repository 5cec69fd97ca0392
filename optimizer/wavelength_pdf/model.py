"""The sampling model's fixed quantities, in one place (design §1).

A table holds ``N_DENSITIES`` piecewise-linear densities over one grid of nodes; each
integrates to 1 by the trapezoid rule, which is exact for piecewise-linear functions. The
default grid is 380, 385, ..., 780 nm, the range of the headerless 4 x 81 layout (design §2).
"""
from __future__ import annotations

import numpy as np

#: Number of densities in a table (design §1).
N_DENSITIES = 4
#: Default wavelength range of a table, nm (design §1).
RANGE: tuple[float, float] = (380.0, 780.0)
#: Default node spacing, nm (design §1).
STEP = 5.0
#: Default table grid: RANGE in STEP-nm steps (81 nodes).
DEFAULT_GRID = np.linspace(RANGE[0], RANGE[1], int(round((RANGE[1] - RANGE[0]) / STEP)) + 1)


def trapezoid(grid: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Integral over ``grid`` along the last axis of piecewise-linear ``values`` (exact).

    Written out rather than ``np.trapezoid`` so that every caller sums in the same order
    (tables written normalized read back bit for bit)."""
    grid = np.asarray(grid, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    return np.sum(0.5 * (values[..., 1:] + values[..., :-1]) * np.diff(grid), axis=-1)
