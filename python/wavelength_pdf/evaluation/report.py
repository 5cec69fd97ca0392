"""Tables and plots of an evaluation: error against spp and against render time.

- :func:`markdown_table`: one line per (scene, illuminant, spp) with the mean CIEDE2000 and the
  seconds of each method side by side, plus the baseline/table error ratio (the shape of the
  published comparison).
- :func:`plot_error`: mean error against spp and against seconds, log-log, one line a method.
- :func:`plot_error_maps`: false-colour per-pixel CIEDE2000 maps, one panel an image.
- :func:`plot_summary`: error against spp and against seconds for many jobs, one row a job.
- :func:`write_report`: a Markdown report of a grid, with every job's plots and colour bar;
  :func:`report_images` lists the files it shows.
"""
from __future__ import annotations

import math
import os
import re
from collections import defaultdict
from pathlib import Path
from typing import Sequence

from wavelength_pdf import extras

matplotlib = extras.module("matplotlib", "evaluation")  # a clear error when the extra is absent
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import ticker  # noqa: E402

from wavelength_pdf.evaluation.protocol import Config, Row  # noqa: E402

STYLE = {"uniform": ("tab:red", "o"), "visible": ("tab:blue", "s"), "table": ("tab:green", "^")}


def _grouped(rows: Sequence[Row]):
    groups: dict[tuple[str, str, int], dict[str, Row]] = defaultdict(dict)
    for r in rows:
        groups[(r.scene, r.illuminant, r.spp)][r.method] = r
    return groups


def _error_cell(r: Row) -> str:
    sd = f" ± {r.mean_sd:.3f}" if r.seeds > 1 and math.isfinite(r.mean_sd) else ""
    return f"{r.mean:.3f}{sd} ({r.median:.3f} / {r.p95:.3f})"


def ratio_and_error(base: Row, ours: Row) -> tuple[float, float]:
    """``base.mean / ours.mean`` and its standard error from the seeds' spread (NaN with one seed).

    Each mean averages ``seeds`` images, so its standard error is ``mean_sd / sqrt(seeds)``;
    relative errors add in quadrature (first order)."""
    r = base.mean / ours.mean
    if base.seeds < 2 or ours.seeds < 2:
        return r, float("nan")
    rel = math.hypot(base.mean_sd / base.mean / math.sqrt(base.seeds),
                     ours.mean_sd / ours.mean / math.sqrt(ours.seeds))
    return r, r * rel


def _ratio_cell(base: Row, ours: Row) -> str:
    r, err = ratio_and_error(base, ours)
    return f"{r:.2f} ± {err:.2f}" if math.isfinite(err) else f"{r:.2f}"


def markdown_table(rows: Sequence[Row], baseline: str = "uniform", ours: str = "table",
                   published: dict[tuple[str, str], str] | None = None) -> str:
    """The results as a Markdown table: mean dE2000 (median, p95) and seconds per method.

    With several seeds, the mean carries ± the standard deviation of the per-seed means.
    ``published`` maps (scene, illuminant) to the published ratio, shown in a last column on
    each job's line at its highest spp (the published figures are at convergence)."""
    methods = list(dict.fromkeys(r.method for r in rows))
    head = ["scene", "illuminant", "spp"] + [f"{m} ΔE mean (median / p95)" for m in methods] + \
           [f"{m} s" for m in methods]
    ratio = baseline in methods and ours in methods
    if ratio:
        head.append(f"{baseline}/{ours} mean ΔE")
    if published is not None:
        head.append("published ratio")
        top = {}
        for r in rows:
            top[(r.scene, r.illuminant)] = max(top.get((r.scene, r.illuminant), 0), r.spp)
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (scene, illum, spp), by in sorted(_grouped(rows).items()):
        cells = [scene, illum, str(spp)]
        cells += [_error_cell(by[m]) if m in by else "" for m in methods]
        cells += [f"{by[m].seconds:.3g}" if m in by else "" for m in methods]
        if ratio:
            cells.append(_ratio_cell(by[baseline], by[ours]) if baseline in by and ours in by else "")
        if published is not None:
            cells.append((published.get((scene, illum)) or "–") if spp == top[(scene, illum)] else "")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _log_axes(ax) -> None:
    """Log-log axes with plain-number ticks at 1, 2, 5 x 10^k (short spans still get labels)."""
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(ticker.FormatStrFormatter("%g"))
        axis.set_minor_formatter(ticker.NullFormatter())
    ax.grid(True, which="both", alpha=0.3)


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
        _log_axes(ax)
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
    height, width = next(iter(maps.values())).shape[:2]
    panel = 2.4 * height / width + 0.3  # the image's aspect plus room for the panel's title
    fig, axes = plt.subplots(len(methods), len(spps), figsize=(2.4 * len(spps) + 1, panel * len(methods) + 0.4),
                             squeeze=False, constrained_layout=True)
    im = None
    for i, m in enumerate(methods):
        for j, s in enumerate(spps):
            ax = axes[i][j]
            ax.set_xticks([])
            ax.set_yticks([])
            if (m, s) in maps:
                im = ax.imshow(maps[(m, s)], cmap="inferno", vmin=0.0, vmax=vmax, interpolation="nearest")
                ax.set_title(f"{m}, {s} spp: {maps[(m, s)].mean():.2f}", fontsize=8)
    if im is not None:
        fig.colorbar(im, ax=axes, shrink=0.8, label="CIEDE2000")
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_summary(rows: Sequence[Row], path: Path, title: str = "") -> None:
    """Mean CIEDE2000 against spp and against seconds, log-log, one row of panels per job."""
    jobs = list(dict.fromkeys((r.scene, r.illuminant) for r in rows))
    fig, axes = plt.subplots(len(jobs), 2, figsize=(9, 2.6 * len(jobs) + 0.6), squeeze=False,
                             constrained_layout=True)
    for (scene, illum), (ax_spp, ax_t) in zip(jobs, axes):
        mine = [r for r in rows if (r.scene, r.illuminant) == (scene, illum)]
        for method in dict.fromkeys(r.method for r in mine):
            rs = sorted((r for r in mine if r.method == method), key=lambda r: r.spp)
            colour, marker = STYLE.get(method, ("k", "x"))
            ax_spp.loglog([r.spp for r in rs], [r.mean for r in rs], marker=marker, color=colour, label=method)
            ax_t.loglog([r.seconds for r in rs], [r.mean for r in rs], marker=marker, color=colour, label=method)
        ax_spp.set_title(f"{scene}: {illum}", fontsize=9)
        ax_t.set_title("same, against wall-clock seconds", fontsize=9)
        ax_spp.set_ylabel("mean CIEDE2000")
        for ax in (ax_spp, ax_t):
            _log_axes(ax)
    axes[-1][0].set_xlabel("samples per pixel")
    axes[-1][1].set_xlabel("render time (s)")
    axes[0][0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_report(path: Path, title: str, jobs: Sequence[tuple[Path, Sequence[Row]]], config: Config,
                 published: dict[tuple[str, str], str] | None = None) -> None:
    """A Markdown report of a grid: settings, the results table, the summary plot, and per job
    its colour bar, error plots and error maps (links relative to the report)."""
    path = Path(path)
    rows = [r for _, job in jobs for r in job]
    rel = lambda p: os.path.relpath(p, path.parent)  # noqa: E731
    res = config.resolution
    size = f"{res[0]}x{res[1]} pixels" if isinstance(res, tuple) else \
        (f"the scenes' film size times {res:g}" if res else "the scenes' film size")
    lines = [f"# {title}", "",
             f"- Images: {size}; wavelengths {config.lo:g}-{config.hi:g} nm; methods "
             f"{', '.join(config.methods)}; spp {', '.join(map(str, config.spp))}; "
             f"{config.seeds} seed(s) per image (± is the standard deviation of the per-seed means).",
             f"- Ground truth: {config.truth_method} sampling, {config.truth_spp} spp, its own seed"
             + (f" ({config.truth_chunks} independent renders of {config.truth_spp // config.truth_chunks} spp, "
                "merged weighted by spp)." if config.truth_chunks > 1 else "."),
             "- Error: per-pixel CIEDE2000 against the ground truth (design §6): mean (median / 95th "
             "percentile). Seconds: wall clock of the renderer process, start-up included.", "",
             markdown_table(rows, published=published), "", f"![summary]({rel(path.parent / 'summary.png')})", ""]
    for folder, job in jobs:
        head = f"{job[0].scene}: {job[0].illuminant}" if job else folder.name
        bar = [f"![colour bar]({rel(folder / 'colour-bar.png')})", ""] if (folder / "colour-bar.png").is_file() else []
        lines += [f"## {head}", "", *bar,
                  f"![error against spp and time]({rel(folder / 'error-vs-spp-and-time.png')})", "",
                  f"![error maps]({rel(folder / 'error-maps.png')})", ""]
    path.write_text("\n".join(lines))


#: An image link as :func:`write_report` writes it: ``![label](relative/path)``.
_IMAGE_LINK = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def report_images(path: Path) -> list[str]:
    """The images a report written by :func:`write_report` shows, as paths relative to it."""
    return list(dict.fromkeys(_IMAGE_LINK.findall(Path(path).read_text())))
