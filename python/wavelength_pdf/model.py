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


#: Most table nodes the optimizer works with (design §2.3): 0.1 nm steps over the default
#: range. Its solvers hold dense interpolation matrices between the table grid and its
#: coarse levels, whose memory grows with the square of the node count (about 33 GB at
#: 0.01 nm steps, 40 001 nodes); at this limit it needs ~0.45 GB beyond its ~0.7 GB of code
#: (measured peak resident size with D65: 0.76 GB at 401 nodes, 0.88 GB at 2001). Any table
#: the optimizer can write is far below the readers' 64 MiB file limit (~0.5 MB).
MAX_TABLE_NODES = 4001

#: The optimizer's own memory (code, JAX, colour data) before any problem, bytes.
OPTIMIZER_BASE_BYTES = 0.7e9

#: Bytes per table node squared (the interpolation matrices of the table grid and its
#: coarsest level: 8 + 8 / 4, times 2 for the copies JAX holds).
TABLE_BYTES_PER_NODE2 = 20
#: Bytes per objective node that one evaluation and its gradient hold at their peak (the
#: u-quadrature's arrays: 4 densities x 4 breakpoints a node x 4 points x ~30 arrays).
OBJECTIVE_BYTES_PER_NODE = 30_000


def optimizer_memory(table_nodes: int, objective_nodes: int = 0) -> float:
    """Rough memory the optimizer needs beyond its ~0.7 GB of code, in bytes."""
    return TABLE_BYTES_PER_NODE2 * float(table_nodes) ** 2 + OBJECTIVE_BYTES_PER_NODE * float(
        max(objective_nodes, table_nodes))


def _gb(n_bytes: float) -> str:
    return f"{n_bytes / 1e9:.3g} GB"


class TooLargeError(ValueError):
    """A problem that cannot fit the optimizer's memory bounds (design §2.3)."""


def check_table_nodes(n: int | float, what: str) -> None:
    """Refuse a table grid of more than ``MAX_TABLE_NODES`` nodes, naming the size it
    would need; ``what`` says where the grid came from (e.g. ``--grid-step 0.01``)."""
    if n > MAX_TABLE_NODES:
        raise TooLargeError(
            f"{what} gives a table of {n:.0f} nodes: the optimizer would need about "
            f"{_gb(optimizer_memory(int(n)))} of memory for it; the limit is "
            f"{MAX_TABLE_NODES} nodes (0.1 nm steps over 380-780 nm, design §2.3)")


def physical_memory() -> float:
    """The machine's physical memory in bytes (inf where the system does not say)."""
    import os

    try:
        return float(os.sysconf("SC_PAGE_SIZE")) * float(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return float("inf")


def check_objective_nodes(n: int, table_nodes: int, what: str) -> None:
    """Refuse an objective whose nodes (the union of the spectrum's, after thinning, the
    CMFs' and the table's) would need more memory than the machine has: a spectrum sampled
    far finer than it can matter, over very many samples that do not thin away."""
    need = OPTIMIZER_BASE_BYTES + optimizer_memory(table_nodes, n)
    have = physical_memory()
    if need > have:
        raise TooLargeError(
            f"{what}: the spectrum, the colour matching functions and the table grid have "
            f"{n} distinct nodes in the table's range: the optimizer would need about "
            f"{_gb(need)} of memory, more than this machine's {_gb(have)} (resample the "
            "spectrum more coarsely, design §2.3)")


def trapezoid(grid, values, xp=np):
    """Integral over ``grid`` along the last axis of piecewise-linear ``values`` (exact).

    Written out rather than ``np.trapezoid`` so that every caller sums in the same order
    (tables written normalized read back bit for bit). ``xp`` is the array module: numpy
    (the arrays are taken as float64), or ``jax.numpy`` where the caller is traced."""
    if xp is np:
        grid = np.asarray(grid, dtype=np.float64)
        values = np.asarray(values, dtype=np.float64)
    return xp.sum(0.5 * (values[..., 1:] + values[..., :-1]) * (grid[1:] - grid[:-1]), axis=-1)


def normalize_density(grid, values, xp=np, keep_within: float = 0.0):
    """Each density of ``values`` (along the last axis) divided by its trapezoid mass over
    ``grid``, so that it integrates to 1 (design §1.1): the one normalization of the table
    reader, the sampler, the optimizer and the Mitsuba plugin's table. ``xp`` as for
    :func:`trapezoid` (``jax.numpy`` keeps it traceable and differentiable).

    ``keep_within`` > 0: a density whose mass is within it of 1 is kept as it is (the reader's
    rule, so that a table written normalized reads back bit for bit, design §2.3). The
    caller must not pass a density that is zero everywhere (the readers refuse it)."""
    if xp is np:
        values = np.asarray(values, dtype=np.float64)
    mass = trapezoid(grid, values, xp)
    if keep_within > 0:
        mass = xp.where(xp.abs(mass - 1.0) <= keep_within, 1.0, mass)
    return values / mass[..., None]


def normalized_with_cdf(grid, p, xp=np):
    """One density ``p`` normalized as by :func:`normalize_density`, and its CDF at the nodes
    (F[0] = 0, F[M] = 1 exactly). ``xp`` as for :func:`trapezoid`."""
    seg = 0.5 * (p[1:] + p[:-1]) * (grid[1:] - grid[:-1])
    cum = xp.concatenate([xp.zeros((1,), dtype=seg.dtype), xp.cumsum(seg)])
    total = cum[-1]
    # x / x == 1 exactly in IEEE arithmetic, so F[M] is exactly 1. XLA may sum the prefixes
    # in different orders, so a plateau at the top can come out an ulp above 1: clip.
    return p / total, xp.minimum(cum / total, 1.0)


def product_integrals(x: np.ndarray, s0: np.ndarray, s1: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Per interval of ``x``: the integral of s * c, s linear from ``s0`` to ``s1`` on the
    interval (one value per end, so a spectrum may jump at a node) and ``c`` (n, k) linear
    between its node values; shape (n - 1, k). Simpson's rule, exact for the product of two
    linear functions."""
    h = np.diff(x)[:, None]
    sm = 0.5 * (s0 + s1)[:, None]
    cm = 0.5 * (c[1:] + c[:-1])
    return h * (s0[:, None] * c[:-1] + 4.0 * sm * cm + s1[:, None] * c[1:]) / 6.0
