"""Pictures of a result: a colour bar of C(u) and a plot of the densities (matplotlib, Agg).

- :func:`colour_bar_png`: the estimated colour C(u) for every u in [0, 1], one row per
  sampler (stratified uniform, the initialization, the result) above the exact target. A
  good table gives a result row that looks like the target row everywhere.
- :func:`densities_png`: the four densities of a table over the (peak-normalized) spectrum,
  with their mixture (1/4) sum_k p_k.

Colours are CIE XYZ converted to sRGB by colour-science, all rows with one exposure: the
target is shown at luminance ``TARGET_Y``, so an estimate up to 1/TARGET_Y times too bright
is still below white; brighter ones clip.
"""

from __future__ import annotations

from pathlib import Path

from wavelength_pdf import extras

matplotlib = extras.module("matplotlib", "plots")  # a clear error when the extra is absent
matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from wavelength_pdf.precision import float64  # noqa: E402
from wavelength_pdf.spectra import Spectrum  # noqa: E402
from wavelength_pdf.table import Table  # noqa: E402

__all__ = ["TARGET_Y", "colour_bar_rows", "colour_bar_png", "densities_png", "xyz_to_srgb"]

#: Luminance at which the target colour is shown (relative to sRGB white = 1).
TARGET_Y = 0.4

#: Number of u values across a colour bar.
N_U = 1024


def xyz_to_srgb(xyz: np.ndarray) -> np.ndarray:
    """Display sRGB in [0, 1] (encoded, clipped) of XYZ values (sRGB white has Y = 1)."""
    import colour

    rgb = colour.XYZ_to_sRGB(np.asarray(xyz, dtype=np.float64))
    return np.clip(np.nan_to_num(rgb, nan=0.0), 0.0, 1.0)


def _init_pdfs(problem) -> np.ndarray | None:
    """The method's initialization (equal-mass partition, :mod:`wavelength_pdf.init`)."""
    from wavelength_pdf import init

    return np.asarray(init.equal_mass_partition(problem), dtype=np.float64)


@float64
def colour_bar_rows(spectrum: Spectrum, table: Table, init_pdfs: np.ndarray | None = None,
                    n_u: int = N_U) -> tuple[list[str], np.ndarray]:
    """Labels and XYZ of the colour bar rows, shape (rows, n_u, 3), scaled so c has Y = 1.

    Rows: stratified uniform, initialization (when known), result, target.
    """
    from wavelength_pdf import objective, uniform
    from wavelength_pdf.problem import make_problem

    grid = np.asarray(table.grid, dtype=np.float64)
    problem = make_problem(spectrum, grid)
    u = (np.arange(n_u) + 0.5) / n_u  # pixel centres
    c = np.asarray(objective.target(problem), dtype=np.float64)
    labels, rows = [], []
    labels.append("uniform")
    rows.append(np.asarray(uniform.uniform_estimate(problem, u)))
    if init_pdfs is None:
        init_pdfs = _init_pdfs(problem)
    if init_pdfs is not None:
        labels.append("initialization")
        rows.append(np.asarray(objective.estimate(problem, init_pdfs, u)))
    labels.append("result")
    rows.append(np.asarray(objective.estimate(problem, table.pdfs, u)))
    labels.append("target")
    rows.append(np.broadcast_to(c, (n_u, 3)))
    return labels, np.stack(rows) / c[1]


def colour_bar_png(path: str | Path, spectrum: Spectrum, table: Table,
                   init_pdfs: np.ndarray | None = None) -> None:
    """Write the colour bar of C(u) (rows: uniform, initialization, result, target) as PNG."""
    labels, xyz = colour_bar_rows(spectrum, table, init_pdfs)
    rgb = xyz_to_srgb(xyz * TARGET_Y)
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(labels) + 0.9), dpi=120)
    ax.imshow(rgb, aspect="auto", interpolation="nearest", extent=(0, 1, len(labels), 0))
    ax.set_yticks(np.arange(len(labels)) + 0.5)
    ax.set_yticklabels(labels)
    ax.set_xlabel("u (one random number for all four wavelengths)")
    ax.set_title(f"estimated colour C(u): {spectrum.name}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def densities_png(path: str | Path, spectrum: Spectrum, table: Table) -> None:
    """Write a plot of the four densities (1/nm) over the peak-normalized spectrum as PNG."""
    grid = np.asarray(table.grid, dtype=np.float64)
    lo, hi = grid[0], grid[-1]
    fig, ax = plt.subplots(figsize=(8, 4), dpi=120)
    # The spectrum at its own resolution, clipped to the table range.
    keep = (spectrum.wavelengths >= lo) & (spectrum.wavelengths <= hi)
    lam = np.concatenate([[lo], spectrum.wavelengths[keep], [hi]])
    val = spectrum(lam)
    peak = val.max() if val.max() > 0 else 1.0
    ax2 = ax.twinx()
    ax2.fill_between(lam, val / peak, color="0.85", step=None, zorder=0, label="spectrum")
    ax2.set_ylim(0, 1.05)
    ax2.set_ylabel("spectrum (peak = 1)")
    ax.set_zorder(ax2.get_zorder() + 1)
    ax.patch.set_visible(False)
    colours = ["tab:blue", "tab:green", "tab:orange", "tab:red"]
    for k in range(table.pdfs.shape[0]):
        ax.plot(grid, table.pdfs[k], color=colours[k % 4], lw=1.4, label=f"p{k}")
    ax.plot(grid, table.pdfs.mean(axis=0), color="k", lw=1.0, ls="--", label="mixture")
    ax.set_xlim(lo, hi)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("density (1/nm)")
    ax.set_title(f"wavelength densities: {spectrum.name}", fontsize=10)
    handles, labels = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(handles + h2, labels + l2, loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
