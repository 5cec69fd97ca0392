"""Tables and plots of an evaluation: error against spp and against render time.

- :func:`markdown_table`: one line per (scene, illuminant, spp) with the mean CIEDE2000 and the
  seconds of each method side by side, plus the baseline/table error ratio (the shape of the
  published comparison).
- :func:`plot_error`: mean error against spp and against seconds, log-log, one line a method.
- :func:`plot_error_maps`: false-colour per-pixel CIEDE2000 maps, one panel an image.
"""
from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from wavelength_pdf.evaluation.protocol import Row  # noqa: E402

STYLE = {"uniform": ("tab:red", "o"), "visible": ("tab:blue", "s"), "table": ("tab:green", "^")}


def _grouped(rows: Sequence[Row]):
    groups: dict[tuple[str, str, int], dict[str, Row]] = defaultdict(dict)
    for r in rows:
        groups[(r.scene, r.illuminant, r.spp)][r.method] = r
    return groups


def markdown_table(rows: Sequence[Row], baseline: str = "uniform", ours: str = "table") -> str:
    """The results as a Markdown table: mean dE2000 (median, p95) and seconds per method."""
    methods = list(dict.fromkeys(r.method for r in rows))
    head = ["scene", "illuminant", "spp"] + [f"{m} ΔE mean (median / p95)" for m in methods] + \
           [f"{m} s" for m in methods]
    ratio = baseline in methods and ours in methods
    if ratio:
        head.append(f"{baseline}/{ours} mean ΔE")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (scene, illum, spp), by in sorted(_grouped(rows).items()):
        cells = [scene, illum, str(spp)]
        cells += [f"{by[m].mean:.3f} ({by[m].median:.3f} / {by[m].p95:.3f})" if m in by else "" for m in methods]
        cells += [f"{by[m].seconds:.2f}" if m in by else "" for m in methods]
        if ratio:
            cells.append(f"{by[baseline].mean / by[ours].mean:.2f}" if baseline in by and ours in by else "")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot_error(rows: Sequence[Row], path: Path, title: str = "") -> None:
    """Mean CIEDE2000 against spp (left) and against render seconds (right), log-log."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for method in dict.fromkeys(r.method for r in rows):
        rs = sorted((r for r in rows if r.method == method), key=lambda r: r.spp)
        colour, marker = STYLE.get(method, ("k", "x"))
        axes[0].loglog([r.spp for r in rs], [r.mean for r in rs], marker=marker, color=colour, label=method)
        axes[1].loglog([r.seconds for r in rs], [r.mean for r in rs], marker=marker, color=colour, label=method)
    axes[0].set_xlabel("samples per pixel")
    axes[1].set_xlabel("render time (s, wall clock)")
    for ax in axes:
        ax.set_ylabel("mean CIEDE2000 vs ground truth")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_error_maps(maps: dict[tuple[str, int], np.ndarray], path: Path, title: str = "") -> None:
    """False-colour per-pixel CIEDE2000 maps: rows are methods, columns spp (one colour scale)."""
    methods = list(dict.fromkeys(m for m, _ in maps))
    spps = sorted({s for _, s in maps})
    vmax = max(float(np.percentile(e, 99)) for e in maps.values())
    fig, axes = plt.subplots(len(methods), len(spps), figsize=(2.4 * len(spps) + 1, 2.4 * len(methods)),
                             squeeze=False, constrained_layout=True)
    im = None
    for i, m in enumerate(methods):
        for j, s in enumerate(spps):
            ax = axes[i][j]
            ax.set_xticks([])
            ax.set_yticks([])
            if (m, s) in maps:
                im = ax.imshow(maps[(m, s)], cmap="inferno", vmin=0.0, vmax=vmax)
                ax.set_title(f"{m}, {s} spp: {maps[(m, s)].mean():.2f}", fontsize=8)
    if im is not None:
        fig.colorbar(im, ax=axes, shrink=0.8, label="CIEDE2000")
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=110)
    plt.close(fig)
