"""The evaluation protocol (SPEC 6) for one scene and one lamp spectrum.

1. A copy of the scene lit by the spectrum (cut to the table's range), at the evaluation's
   resolution (:mod:`.scene_edit`).
2. The spectrum's table, optimized once and cached.
3. A ground truth at high spp (cached), and for each sampler (stratified uniform over the
   table's range, pbrt-v4's visible sampling, the table) and each spp an image and its render
   time. The truth is rendered with the table by default, with a seed of its own: every
   sampler is unbiased, and the table's has the least colour noise per sample, so the truth's
   own noise caps the measured error ratios least.
4. Per pixel CIEDE2000 against the ground truth: mean, median, 95th percentile.

Everything lands in one output folder: ``scene.pbrt``, ``table.csv``, ``renders/``,
``results.csv`` and the plots of :mod:`.report`.
"""
from __future__ import annotations

import csv
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from wavelength_pdf.evaluation import metrics, render as rendering
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.exr import read_rgb
from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.table import read_table

DEFAULT_SPP = (16, 64, 256, 512)
DEFAULT_METHODS = ("uniform", "visible", "table")


@dataclass
class Config:
    """What one evaluation renders. Every image uses the same range, resolution and depth."""

    spp: Sequence[int] = DEFAULT_SPP
    methods: Sequence[str] = DEFAULT_METHODS
    truth_spp: int = 8192
    truth_method: str = "table"
    #: (width, height), a factor on the scene's own film size, or None to keep it.
    resolution: tuple[int, int] | float | None = (128, 128)
    seed: int = 1
    #: Images per (method, spp), with seeds ``seed, seed + 1, ...``: their spread is the noise
    #: of the mean error (``Row.mean_sd``).
    seeds: int = 1
    nthreads: int | None = None
    lo: float = 380.0
    hi: float = 780.0
    #: The renderer; None: :func:`render.find_pbrt`'s lookup.
    pbrt: Path | None = None


@dataclass
class Row:
    """One line of the results table."""

    scene: str
    illuminant: str
    method: str
    spp: int
    mean: float
    median: float
    p95: float
    seconds: float
    image: str
    #: How many seeds the figures average, and the standard deviation of the per-seed mean
    #: errors (NaN with one seed).
    seeds: int = 1
    mean_sd: float = float("nan")


@dataclass
class Evaluation:
    rows: list[Row] = field(default_factory=list)
    truth: Path | None = None
    truth_seconds: float = 0.0
    table: Path | None = None
    scene: Path | None = None
    error_maps: dict[tuple[str, int], np.ndarray] = field(default_factory=dict)


def ensure_table(spectrum: Spectrum, path: Path, lo: float, hi: float, step: float | str = "auto",
                 progress: Callable[[int, float], None] | None = None) -> Path:
    """The spectrum's optimized table at ``path``, optimized only when it is not there yet."""
    if path.is_file():
        read_table(path)  # a damaged cache is an error, not silently reused
        return path
    from wavelength_pdf.produce import make_grid, optimize_one

    outcome = optimize_one(spectrum, path, make_grid(lo, hi, step), None, 0, None, progress)
    if not outcome.written:
        raise RuntimeError(f"{spectrum.source}: the optimized table was not accepted "
                           f"({outcome.result.reason})")
    return path


def evaluate(scene: Path, spectrum: Spectrum, outdir: Path, config: Config = Config(), *,
             table: Path | None = None, scene_name: str | None = None,
             progress: Callable[[str], None] | None = None,
             optimizer_progress: Callable[[int, float], None] | None = None) -> Evaluation:
    """Run the protocol; returns the rows (also written to ``outdir/results.csv``).

    ``progress`` hears what is being rendered; ``optimizer_progress(step, J)`` follows the
    table's optimization when there is one to do."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda msg: None)
    ev = Evaluation()
    ev.scene = edit_scene(scene, spectrum, outdir / "scene.pbrt", lo=config.lo, hi=config.hi,
                          resolution=config.resolution)
    if table is None:
        say("optimizing the table")
    ev.table = table or ensure_table(spectrum, outdir / "table.csv", config.lo, config.hi,
                                     progress=optimizer_progress)
    samplers = rendering.samplers(ev.table, config.lo, config.hi)
    unknown = set(config.methods) - set(samplers)
    if unknown:
        raise ValueError(f"unknown methods {sorted(unknown)}; choose from {sorted(samplers)}")

    say(f"ground truth: {config.truth_method}, {config.truth_spp} spp")
    gt = rendering.render(ev.scene, outdir / "renders" / f"truth-{config.truth_method}-{config.truth_spp}.exr",
                          samplers[config.truth_method], config.truth_spp,
                          seed=10_000 + config.seed, nthreads=config.nthreads, pbrt=config.pbrt,
                          on_percent=lambda pct: say(f"ground truth: {config.truth_method}, "
                                                     f"{config.truth_spp} spp, {pct}%"))
    ev.truth, ev.truth_seconds = gt.image, gt.seconds
    truth = read_rgb(gt.image)
    name = scene_name or Path(scene).parent.name or Path(scene).stem
    seeds = [config.seed + k for k in range(max(1, config.seeds))]
    # Methods interleaved at each spp and seed, so that a change in the machine's load over
    # the run does not favour one method's render times.
    results: dict[tuple[str, int], list[tuple[metrics.ErrorStats, float, Path, np.ndarray]]] = {}
    for spp in config.spp:
        for seed in seeds:
            for method in config.methods:
                say(f"{method}: {spp} spp, seed {seed}")
                r = rendering.render(ev.scene, outdir / "renders" / f"{method}-{spp}-seed{seed}.exr",
                                     samplers[method], spp, seed=seed, nthreads=config.nthreads,
                                     pbrt=config.pbrt)
                emap = metrics.delta_e_map(read_rgb(r.image), truth)
                results.setdefault((method, spp), []).append(
                    (metrics.ErrorStats.of(emap), r.seconds, r.image, emap))
    for method in config.methods:
        for spp in config.spp:
            runs = results[(method, spp)]
            means = np.array([st.mean for st, *_ in runs])
            ev.error_maps[(method, spp)] = runs[0][3]
            ev.rows.append(Row(name, spectrum.name, method, spp, float(means.mean()),
                               float(np.mean([st.median for st, *_ in runs])),
                               float(np.mean([st.p95 for st, *_ in runs])),
                               float(np.mean([sec for _, sec, *_ in runs])),
                               str(runs[0][2].relative_to(outdir)), len(runs),
                               float(means.std(ddof=1)) if len(runs) > 1 else float("nan")))
    write_rows(outdir / "results.csv", ev.rows)
    return ev


def write_rows(path: Path, rows: Sequence[Row]) -> None:
    """The results table as CSV (one row per scene, illuminant, method and spp)."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(Row.__dataclass_fields__))
        w.writeheader()
        for r in rows:
            w.writerow(asdict(r))
