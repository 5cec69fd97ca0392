"""The evaluation protocol (design §6) for one scene and one lamp spectrum.

1. A copy of the scene lit by the spectrum (cut to the table's range), at the evaluation's
   resolution (:mod:`.scene_edit`).
2. The spectrum's table, optimized once and cached.
3. A ground truth at high spp (cached), rendered as ``truth_chunks`` independent images (seeds
   of their own, equal spp) merged weighted by spp (:func:`merge_chunks`), and for each sampler (stratified uniform over the
   table's range, pbrt-v4's visible sampling, the table) and each spp an image and its render
   time. The truth is rendered with the table by default, with a seed of its own: every
   sampler is unbiased, and the table's has the least colour noise per sample, so the truth's
   own noise caps the measured error ratios least.
4. Per pixel CIEDE2000 against the ground truth: mean, median, 95th percentile.

:func:`plan` lists the renders of one evaluation (:class:`RenderJob`, each an independent,
idempotent task) and :func:`finish` turns their images into rows; :func:`evaluate` runs them
in this process, :mod:`.cluster` on a Dask cluster. Everything lands in one output folder: ``scene.pbrt``, ``table.csv``, ``renders/``,
``results.csv`` and the plots of :mod:`.report`.
"""
from __future__ import annotations

import csv
import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from wavelength_pdf.evaluation import metrics, render as rendering
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.exr import read_rgb, write_rgb
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
    #: The truth is this many renders of ``truth_spp / truth_chunks`` spp each, merged.
    truth_chunks: int = 1
    #: (width, height), a factor on the scene's own film size, or None to keep it.
    resolution: tuple[int, int] | float | None = (128, 128)
    seed: int = 1
    #: Images per (method, spp), with seeds ``seed, seed + 1, ...``: their spread is the noise
    #: of the mean error (``Row.mean_sd``).
    seeds: int = 1
    nthreads: int | None = None
    lo: float = 380.0
    hi: float = 780.0
    #: The renderer; None: :func:`wavelength_pdf.renderer.find_pbrt`'s lookup.
    pbrt: Path | None = None
    #: ``--reflectances``: the surface colours the table is optimized for (design §4.5),
    #: loaded once per job (:func:`wavelength_pdf.reflectances.load_reflectances`); None:
    #: the white surface of design §4.1.
    reflectances: str | None = None


#: The spectrum name that evaluates a scene under its own emitters (design §6.1): the table
#: is optimized for the scene's total emission (``optimize --whole-scene``).
WHOLE_SCENE = "whole-scene"


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
                 progress: Callable[[int, float], None] | None = None, reflectances=None,
                 objective: str = "J") -> Path:
    """The spectrum's optimized table at ``path``, optimized only when it is not there yet
    (with ``reflectances``, a :class:`~wavelength_pdf.reflectances.ReflectanceSet`, for those
    surface colours; for ``objective``, design §4.6, at its default spp)."""
    if path.is_file():
        read_table(path)  # a damaged cache is an error, not silently reused
        return path
    from wavelength_pdf.produce import make_grid, optimize_one

    outcome = optimize_one(spectrum, path, make_grid(lo, hi, step), None, 0, None, progress,
                           reflectances=reflectances, objective=objective)
    if not outcome.written:
        raise RuntimeError(f"{spectrum.source}: the optimized table was not accepted "
                           f"({outcome.result.reason})")
    return path


@dataclass(frozen=True)
class RenderJob:
    """One render of the protocol: a picklable, idempotent task (a finished image is reused)."""

    scene: Path
    out: Path
    sampler: rendering.Sampler
    spp: int
    seed: int
    #: None: :func:`wavelength_pdf.renderer.find_pbrt`'s lookup.
    pbrt: Path | None = None

    def run(self, nthreads: int | None = None, on_percent: Callable[[int], None] | None = None
            ) -> rendering.Render:
        return rendering.render(self.scene, self.out, self.sampler, self.spp, seed=self.seed,
                                nthreads=nthreads, pbrt=self.pbrt, on_percent=on_percent)

    def done(self) -> rendering.Render | None:
        """The cached image if it is there and its inputs are unchanged (the table must exist)."""
        try:
            return rendering.cached(self.out, rendering.render_key(self.scene, self.sampler, self.spp,
                                                                   self.seed, self.pbrt))
        except OSError:  # the table is not optimized yet
            return None


@dataclass
class Plan:
    """The renders of one evaluation (scene x spectrum), before any of them ran."""

    name: str
    illuminant: str
    outdir: Path
    scene: Path
    table: Path
    config: Config
    #: The chunks of the ground truth, and the image they merge into.
    truth_chunks: list[RenderJob]
    truth: Path
    #: The compared images by (method, spp, seed), methods interleaved at each spp and seed,
    #: so that a change in the machine's load over the run does not favour one method's times.
    images: dict[tuple[str, int, int], RenderJob]


def truth_seed(config: Config, chunk: int) -> int:
    """The seed of ground-truth chunk ``chunk``: apart from the compared images' seeds, and
    chunk 0 is the seed of a one-render truth."""
    return 10_000 + config.seed + 1_000 * chunk


def check_config(config: Config) -> None:
    """Raise ValueError for a configuration that cannot run (before any long work)."""
    k = config.truth_chunks
    if k < 1 or config.truth_spp < 1 or config.truth_spp % k:
        raise ValueError(f"--truth-chunks must be at least 1 and divide --truth-spp into equal chunks; "
                         f"got {k} chunks of {config.truth_spp} spp")
    if config.seeds < 1:
        raise ValueError(f"--seeds must be at least 1, got {config.seeds}")
    bad = [s for s in config.spp if s < 1]
    if bad:
        raise ValueError(f"--spp must be positive, got {bad}")


def plan(scene: Path, spectrum: Spectrum, outdir: Path, config: Config = Config(), *,
         table: Path | None = None, scene_name: str | None = None,
         keep_emitters: bool = False) -> Plan:
    """Write the lit scene copy and list the renders of the protocol (none is run).

    Without ``table`` the renders use ``outdir/table.csv``, which :func:`ensure_table` makes.
    ``keep_emitters``: the copy keeps the scene's own emitters (the whole-scene mode, where
    ``spectrum`` is the scene's total emission) instead of being lit by ``spectrum``."""
    check_config(config)
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    edited = edit_scene(scene, None if keep_emitters else spectrum, outdir / "scene.pbrt",
                        lo=config.lo, hi=config.hi, resolution=config.resolution)
    table = Path(table) if table else outdir / "table.csv"
    samplers = rendering.samplers(table, config.lo, config.hi)
    unknown = (set(config.methods) | {config.truth_method}) - set(samplers)
    if unknown:
        raise ValueError(f"unknown methods {sorted(unknown)}; choose from {sorted(samplers)}")
    renders = outdir / "renders"
    k, method = config.truth_chunks, config.truth_method
    base = f"truth-{method}-{config.truth_spp}"
    truth = renders / (f"{base}.exr" if k == 1 else f"{base}-x{k}.exr")
    chunks = [RenderJob(edited, truth if k == 1 else renders / f"{base}-x{k}-chunk{i}.exr",
                        samplers[method], config.truth_spp // k, truth_seed(config, i), config.pbrt)
              for i in range(k)]
    images = {(m, spp, seed): RenderJob(edited, renders / f"{m}-{spp}-seed{seed}.exr", samplers[m], spp, seed,
                                        config.pbrt)
              for spp in config.spp for seed in seeds_of(config) for m in config.methods}
    return Plan(scene_name or Path(scene).parent.name or Path(scene).stem, spectrum.name, outdir, edited,
                table, config, chunks, truth, images)


def seeds_of(config: Config) -> list[int]:
    return [config.seed + k for k in range(max(1, config.seeds))]


def merge_chunks(images: Sequence[np.ndarray], spp: Sequence[int]) -> np.ndarray:
    """The spp-weighted mean of independent renders of one scene (float64).

    Each image is an unbiased estimate averaging its own ``spp`` samples per pixel, so their
    spp-weighted mean is the estimate of all the samples together."""
    if len(images) != len(spp) or not images:
        raise ValueError(f"merge_chunks: {len(images)} images and {len(spp)} sample counts")
    w = np.asarray(spp, dtype=np.float64)
    if np.any(w <= 0) or not np.all(np.isfinite(w)):
        raise ValueError(f"merge_chunks: sample counts must be positive, got {list(spp)}")
    shapes = {np.shape(im) for im in images}
    if len(shapes) != 1:
        raise ValueError(f"merge_chunks: images of different shapes {sorted(shapes)}")
    total = np.zeros(np.shape(images[0]), dtype=np.float64)
    for im, wi in zip(images, w):
        total += wi * np.asarray(im, dtype=np.float64)
    return total / w.sum()


def merge_truth(chunks: Sequence[rendering.Render], jobs: Sequence[RenderJob], out: Path) -> rendering.Render:
    """Merge rendered truth chunks into ``out`` (cached by the chunks' keys; written atomically).

    Its seconds are the chunks' summed render times."""
    out = Path(out)
    if len(jobs) == 1 and Path(chunks[0].image) == out:
        return chunks[0]
    keys = [rendering.render_key(j.scene, j.sampler, j.spp, j.seed, j.pbrt) for j in jobs]
    key = rendering.file_digest(extra=json.dumps(keys))
    if (done := rendering.cached(out, key)) is not None:
        return done
    merged = merge_chunks([read_rgb(c.image) for c in chunks], [j.spp for j in jobs])
    tmp = rendering.temporary(out)
    try:
        write_rgb(tmp, merged)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    seconds = float(sum(c.seconds for c in chunks))
    rendering.write_json(out.with_suffix(".json"), {"key": key, "seconds": seconds,
                                                     "chunks": [str(c.image) for c in chunks],
                                                     "spp": [j.spp for j in jobs]})
    return rendering.Render(out, seconds)


def finish(p: Plan, truth: rendering.Render, images: dict[tuple[str, int, int], rendering.Render]) -> Evaluation:
    """Compare the rendered images with the truth; the rows (also written to ``results.csv``)."""
    ev = Evaluation(truth=truth.image, truth_seconds=truth.seconds, table=p.table, scene=p.scene)
    return score(ev, p.name, p.illuminant, p.outdir, p.config, read_rgb(truth.image), images)


def score(ev: Evaluation, name: str, illuminant: str, outdir: Path, config: Config, truth: np.ndarray,
          images: dict[tuple[str, int, int], rendering.Render]) -> Evaluation:
    """Per-pixel CIEDE2000 of every image (keyed by method, spp, seed) against ``truth``; one row
    per method and spp (the seeds averaged, their spread the noise of the mean) appended to
    ``ev`` and written to ``outdir/results.csv``. Shared by every renderer's protocol."""
    results: dict[tuple[str, int], list[tuple[metrics.ErrorStats, float, Path, np.ndarray]]] = {}
    for (method, spp, _), r in images.items():
        emap = metrics.delta_e_map(read_rgb(r.image), truth)
        results.setdefault((method, spp), []).append((metrics.ErrorStats.of(emap), r.seconds, r.image, emap))
    for method in config.methods:
        for spp in config.spp:
            runs = results[(method, spp)]
            means = np.array([st.mean for st, *_ in runs])
            ev.error_maps[(method, spp)] = runs[0][3]
            ev.rows.append(Row(name, illuminant, method, spp, float(means.mean()),
                               float(np.mean([st.median for st, *_ in runs])),
                               float(np.mean([st.p95 for st, *_ in runs])),
                               float(np.mean([sec for _, sec, *_ in runs])),
                               str(Path(runs[0][2]).relative_to(outdir)), len(runs),
                               float(means.std(ddof=1)) if len(runs) > 1 else float("nan")))
    write_rows(Path(outdir) / "results.csv", ev.rows)
    return ev


def evaluate(scene: Path, spectrum: Spectrum, outdir: Path, config: Config = Config(), *,
             table: Path | None = None, scene_name: str | None = None,
             progress: Callable[[str], None] | None = None,
             optimizer_progress: Callable[[int, float], None] | None = None,
             keep_emitters: bool = False, reflectances=None) -> Evaluation:
    """Run the protocol in this process; returns the rows (also written to ``outdir/results.csv``).

    ``progress`` hears what is being rendered; ``optimizer_progress(step, J)`` follows the
    table's optimization when there is one to do."""
    say = progress or (lambda msg: None)
    p = plan(scene, spectrum, outdir, config, table=table, scene_name=scene_name,
             keep_emitters=keep_emitters)
    if table is None:
        say("optimizing the table")
        ensure_table(spectrum, p.table, config.lo, config.hi, progress=optimizer_progress,
                     reflectances=reflectances)
    label = f"ground truth: {config.truth_method}, {config.truth_spp} spp"
    say(label)
    chunks = []
    for i, job in enumerate(p.truth_chunks):
        part = f" (chunk {i + 1} of {len(p.truth_chunks)})" if len(p.truth_chunks) > 1 else ""
        chunks.append(job.run(config.nthreads, on_percent=lambda pct: say(f"{label}{part}, {pct}%")))
    truth = merge_truth(chunks, p.truth_chunks, p.truth)
    images = {}
    for (method, spp, seed), job in p.images.items():
        say(f"{method}: {spp} spp, seed {seed}")
        images[(method, spp, seed)] = job.run(config.nthreads)
    return finish(p, truth, images)


def write_rows(path: Path, rows: Sequence[Row]) -> None:
    """The results table as CSV (one row per scene, illuminant, method and spp)."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(Row.__dataclass_fields__))
        w.writeheader()
        for r in rows:
            w.writerow(asdict(r))
