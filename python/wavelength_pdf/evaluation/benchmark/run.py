"""Planning and running the benchmark's renders (design §6.7), resumable, on a Dask cluster.

A job (:class:`~.grid.Job`) becomes a :class:`JobPlan`: a copy of the scene lit by the lamp at
the job's resolution with its pixel sampler, the tables of every row (shared by all jobs under
one lamp, in ``OUT/tables/LAMP/``), and its renders (:class:`~..protocol.RenderJob`, each an
idempotent task whose finished image is reused):

- each row at each spp with the two seeds of the pair;
- the floor: the ``spd`` table with ``--wavelength-repeats`` at each spp, same seeds;
- the reference: four chunks of a quarter of ``truth_spp`` each, drawn with four different
  samplers (pbrt-v4's visible sampling, and the uniform, ``spd`` and ``luminance`` tables), so
  that the reference does not share the table's wavelengths and a bias of any row shows
  against it; chunks 0 + 2 and 1 + 3 are its two halves (its own noise, :mod:`.measures`).

The baseline tables are written in this process (milliseconds each); the optimized tables
are tasks on the cluster, all finished before the first render is submitted. Scoring reads
the finished images into ``OUT/jobs/.../scores.json`` (cached by the renders' keys).
"""
from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from wavelength_pdf.evaluation import render as rendering
from wavelength_pdf.evaluation.benchmark import grid as G
from wavelength_pdf.evaluation.benchmark import measures
from wavelength_pdf.evaluation.protocol import RenderJob, merge_chunks
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.spectra import Spectrum, load_spectrum
from wavelength_pdf.table import read_table, write_table

#: Wavelength range of every table and of the lamp in the scene copies (design §6.1).
LO, HI = 380.0, 780.0
#: Bumped when the scores of the same images change (a new measure or a fixed one), so that
#: cached ``scores.json`` files are computed again.
SCORES_VERSION = "1"
#: The rows whose tables the optimizer makes for a lamp (tasks on the cluster), by objective.
OPTIMIZED = {"optimized": "J", G.PIXEL: "stratified"}
#: The same for the rows optimized for the scene's own colours (tables in the job's folder).
OPTIMIZED_FOR_COLOURS = {G.SCENE_COLOURS: "J", G.PIXEL_SCENE: "stratified"}
#: The rows whose lamp tables are optimized for a named colour set: row -> (objective, set).
OPTIMIZED_FOR_SET = {G.GENERIC_COLOURS: ("J", "colorchecker")}
#: Samplers of the reference's four chunks.
TRUTH_ROWS = (G.BUILTIN, "uniform", "spd", "luminance")


@dataclass
class JobPlan:
    """The renders and tables of one job."""

    job: G.Job
    outdir: Path
    scene: Path
    spectrum: Spectrum
    tables: dict[str, Path]
    #: The scene's material colours, for the table optimized for them (design §4.5).
    reflectances: object | None = None
    images: dict[tuple[str, int, int], RenderJob] = field(default_factory=dict)
    floor: dict[tuple[int, int], RenderJob] = field(default_factory=dict)
    truth_chunks: list[RenderJob] = field(default_factory=list)
    #: The :data:`~.grid.IMAGE` row's tables by spp (``choose --spp N``'s, made by :func:`run`).
    image_tables: dict[int, Path] = field(default_factory=dict)

    def renders(self) -> list[RenderJob]:
        return [*self.truth_chunks, *self.images.values(), *self.floor.values()]

    def tables_at(self, spp: int) -> dict[str, Path]:
        """Row -> table of the images at ``spp`` (the image row's table for that spp; at an
        spp the job does not render at, e.g. a timing's, its table for the job's highest)."""
        if not self.image_tables:
            return self.tables
        return {**self.tables, G.IMAGE: self.image_tables.get(spp, self.image_tables[max(self.image_tables)])}


def sampler_of(row: str, tables: dict[str, Path], repeats: int = 1, net: bool = False) -> rendering.Sampler:
    """The renderer options of a row: a table through ``--wavelength-pdf``, or pbrt-v4's own
    visible sampling for the check row; ``net``: with ``--wavelength-net`` (design §5.2)."""
    extra: tuple[str, ...] = ("--wavelength-net",) if net else ()
    if row == G.BUILTIN:
        return rendering.Sampler(row, "pbrt-v4 visible (built in)", ("--wavelength-sampling", "visible", *extra))
    args: tuple[str, ...] = ("--wavelength-pdf", str(tables[row]))
    label = f"{row} table"
    if repeats > 1:
        args += ("--wavelength-repeats", str(repeats))
        label += f" x{repeats} wavelengths"
    return rendering.Sampler(row, label, args + extra)


def lamp_folder(out: Path, job: G.Job) -> Path:
    """Where the tables of a job's lamp live (own-lamp scenes: per scene)."""
    return out / "tables" / (job.lamp.key if job.lamp else f"own-{job.scene.key}")


def job_folder(out: Path, job: G.Job) -> Path:
    return out / "jobs" / job.scene.key / job.lamp_key / job.pixel_sampler


def write_scene(job: G.Job, out: Path, spectrum: Spectrum | None, shared: Path) -> Path:
    """The job's scene copy: lit by the lamp (or its own emitters), its resolution, its pixel
    sampler; the glass of water with the project's water body."""
    source = job.scene.path(shared)
    folder = job_folder(out, job)
    if job.scene.water:
        from wavelength_pdf.evaluation.glass_of_water import with_water

        source = with_water(source, folder / "with-water" / "scene.pbrt")
    return edit_scene(source, spectrum, folder / "scene.pbrt", lo=LO, hi=HI, resolution=job.size,
                      pixel_sampler=job.pixel_sampler, cut_emitters=spectrum is None)


def job_spectrum(job: G.Job, out: Path, shared: Path, pbrt: Path | None) -> Spectrum:
    """The lamp's spectrum, or for an own-lamp scene its total emission (design §5.6)."""
    if job.lamp is not None:
        return load_spectrum(job.lamp.spec(shared), lo=LO, hi=HI)
    from wavelength_pdf.scene_spectra import whole_scene_spectrum

    return whole_scene_spectrum(job.scene.path(shared), lo=LO, hi=HI, pbrt=pbrt)


def baseline_tables(spectrum: Spectrum, folder: Path, rows: Sequence[str], job: G.Job,
                    shared: Path) -> dict[str, Path]:
    """Write the rows' tables that need no optimizer (once; reused when present) and name the
    optimized table's path (made by a task). Returns row -> table path."""
    from wavelength_pdf import stratified
    from wavelength_pdf.optimize import starting_table

    folder.mkdir(parents=True, exist_ok=True)
    paths: dict[str, Path] = {}
    makers: dict[str, Callable] = {
        "uniform": lambda: stratified.uniform_table(LO, HI),
        "visible": stratified.visible_table,
        "start": lambda: starting_table(spectrum),
        **{w: (lambda w=w: stratified.stratified_table(spectrum, w, LO, HI)) for w in stratified.WEIGHTS},
    }
    needed = set(rows) | {G.FLOOR_TABLE} | (set(TRUTH_ROWS) - {G.BUILTIN})
    for row in sorted(needed):
        if row in OPTIMIZED or row in OPTIMIZED_FOR_SET:
            paths[row] = folder / f"{row}.csv"
            continue
        if row == "reference" or row in G.COLOUR_ROWS or row == G.IMAGE:
            continue
        path = folder / f"{row}.csv"
        if not path.is_file():
            write_table(path, makers[row]())
        paths[row] = path
    if job.lamp is not None and job.lamp.reference:
        ref = shared / "tables" / "reference-4x81" / f"{job.lamp.reference}.csv"
        if ref.is_file():
            paths["reference"] = ref
    return paths


def plan_job(job: G.Job, out: Path, shared: Path, pbrt: Path | None) -> JobPlan:
    """Write the job's scene copy and tables, and list its renders (none is run)."""
    spectrum = job_spectrum(job, out, shared, pbrt)
    scene = write_scene(job, out, None if job.lamp is None else spectrum, shared)
    tables = baseline_tables(spectrum, lamp_folder(out, job), job.rows, job, shared)
    rows = [*job.rows, *(["reference"] if "reference" in tables else []), G.BUILTIN]
    folder = job_folder(out, job)
    renders = folder / "renders"
    reflectances = None
    if any(row in job.rows for row in G.COLOUR_ROWS):
        from wavelength_pdf.reflectances import load_reflectances
        from wavelength_pdf.spectra import SpectrumError

        try:
            reflectances = load_reflectances("scene", scene=scene, lo=LO, hi=HI, pbrt=pbrt)
            tables.update({row: folder / f"{row}.csv" for row in G.COLOUR_ROWS if row in job.rows})
        except SpectrumError:  # no diffuse colours in the scene (the glass of water): no such row
            rows = [row for row in rows if row not in G.COLOUR_ROWS]
    p = JobPlan(job, folder, scene, spectrum, tables, reflectances)
    if G.IMAGE in job.rows:
        if job.lamp is None or job.pixel_sampler != "sobol":  # one kind of light, the polish's strata
            rows = [row for row in rows if row != G.IMAGE]
        else:
            p.image_tables = {spp: folder / G.image_table_name(spp) for spp in job.spp}
    for spp in job.spp:
        at_spp = p.tables_at(spp)
        for seed in job.seeds:
            for row in rows:
                if row == G.BUILTIN and spp not in job.check_spp:
                    continue
                p.images[(row, spp, seed)] = RenderJob(scene, renders / f"{row}-{spp}-seed{seed}.exr",
                                                       sampler_of(row, at_spp, net=job.wavelength_net), spp,
                                                       seed, pbrt)
            if spp in job.floor_spp:
                p.floor[(spp, seed)] = RenderJob(scene, renders / f"floor-{spp}-seed{seed}.exr",
                                                 sampler_of(G.FLOOR_TABLE, tables, job.floor_repeats,
                                                            job.wavelength_net), spp, seed,
                                                 pbrt)
    k = len(TRUTH_ROWS)
    for i, row in enumerate(TRUTH_ROWS):
        p.truth_chunks.append(RenderJob(scene, renders / f"truth-{job.truth_spp}-chunk{i}-{row}.exr",
                                        sampler_of(row, tables, net=job.wavelength_net), job.truth_spp // k,
                                        10_000 + 1_000 * i, pbrt))
    return p


# --- Running ---------------------------------------------------------------------------


def _table_task(spectrum: Spectrum, path: Path, reflectances=None, objective: str = "J") -> Path:
    from wavelength_pdf.evaluation.cluster import table_task

    return table_task(spectrum, path, LO, HI, reflectances, objective)


def _made_by(row: str, p: JobPlan) -> tuple[object | None, str]:
    """The colours and the objective an optimized row's table is made for."""
    if row in OPTIMIZED_FOR_SET:
        from wavelength_pdf.reflectances import load_reflectances

        objective, colours = OPTIMIZED_FOR_SET[row]
        return load_reflectances(colours, lo=LO, hi=HI), objective
    if row in OPTIMIZED_FOR_COLOURS:
        return p.reflectances, OPTIMIZED_FOR_COLOURS[row]
    return None, OPTIMIZED[row]


def image_transfer_key(p: JobPlan) -> object:
    """What :func:`image_transfer` depends on: jobs with equal keys share one transfer."""
    return p.job.scene.key if p.job.resolution is None else p.outdir


def image_transfer(p: JobPlan, out: Path, shared: Path = G.SHARED, pbrt: Path | None = None):
    """The transfer (with each pixel's spread) the job's :data:`~.grid.IMAGE` tables are chosen
    from: the scene's at its benchmark size (``out/transfer/SCENE``, rendered once), or for a
    job of a size of its own its copy's (its lamp replaced by a flat one). Without the spread's
    cells even on ``--wavelength-net`` runs: with them the choices measured worse
    (docs/benchmark.md, "What the net stratifies of a pixel's spread")."""
    from wavelength_pdf.evaluation import transfer
    from wavelength_pdf.evaluation.benchmark.predict import scene_transfer

    if p.job.resolution is None:
        return scene_transfer(p.job.scene.key, out, shared, pbrt, spread=True)
    return transfer.of_file(p.scene, p.outdir / "transfer", 1.0, pbrt, with_spread=True)


def image_table(p: JobPlan, spp: int, out: Path, shared: Path = G.SHARED, pbrt: Path | None = None,
                say: Callable[[str], None] = lambda m: None, tr=None) -> Path:
    """Write the job's :data:`~.grid.IMAGE` table for ``spp``: ``wavelength-pdf choose --spp
    SPP``'s best with ``--polish --spread`` (:func:`wavelength_pdf.evaluation.choose.for_image`),
    its candidates the simple samplers and the job's J table (``optimized``, made first), from
    ``tr``, the job's :func:`image_transfer` (None: loaded here; loading it is seconds, so a
    caller making many tables passes it)."""
    from wavelength_pdf.evaluation import choose
    from wavelength_pdf.table import Table

    if tr is None:
        tr = image_transfer(p, out, shared, pbrt)
    given = {"optimized": read_table(p.tables["optimized"])} if "optimized" in p.tables else {}
    preds = choose.for_image(p.spectrum, tr, spp, given, polish_evaluations=p.job.polish_evaluations, say=say)
    best = preds[0]
    path = p.image_tables[spp]
    write_table(path, Table(best.table.grid, best.table.pdfs, [
        *best.table.comments, f"{G.IMAGE}: {best.name}, best of {len(preds)} by the predicted image error at "
        f"{spp} spp ({', '.join(f'{q.name} {q.wavelength:.4g}' for q in preds)})"]))
    return path


#: A worker's last transfer (key, Transfer): one at a time, since a spread is large.
_KEPT_TRANSFER: list = [None, None]


def _image_task(p: JobPlan, spp: int, out: Path, shared: Path, pbrt: Path | None) -> Path:
    """:func:`image_table` on a worker, which keeps the last transfer it loaded."""
    from wavelength_pdf import aot

    key = image_transfer_key(p)
    if _KEPT_TRANSFER[0] != key:
        _KEPT_TRANSFER[:] = [None, None]  # the old one freed before the new one loads
        _KEPT_TRANSFER[:] = [key, image_transfer(p, out, shared, pbrt)]
    try:
        return image_table(p, spp, out, shared, pbrt, tr=_KEPT_TRANSFER[1])
    finally:
        aot.clear_memory()  # each choice compiles for its own shapes


def run(plans: Sequence[JobPlan], *, workers: int | None = None, scheduler: str | None = None,
        nthreads: int | None = None, say: Callable[[str], None] | None = None, out: Path | None = None,
        shared: Path = G.SHARED, pbrt: Path | None = None) -> None:
    """Optimize the missing tables and render every image not rendered yet, on a Dask cluster
    (a local one of ``workers`` processes, or the one at ``scheduler``); prints the estimated
    CPU time first and follows the renders with a progress bar. The :data:`~.grid.IMAGE`
    tables (which need the J tables and the scene's transfer) are made after the optimized
    tables, as tasks on the same cluster, each scene's transfer rendered first in this process
    (``out``: the benchmark's folder)."""
    from distributed import as_completed

    from wavelength_pdf import progress
    from wavelength_pdf.evaluation import cluster

    say = say or (lambda msg: print(msg, file=sys.stderr))
    todo = [(p, r) for p in plans for r in p.renders() if r.done() is None or not _table_ready(r)]
    optimize = {p.tables[row]: (p.spectrum, *_made_by(row, p))
                for p in plans for row in (*OPTIMIZED, *OPTIMIZED_FOR_COLOURS, *OPTIMIZED_FOR_SET)
                if row in p.tables and not p.tables[row].is_file()}
    if not todo and not optimize:
        say("benchmark: every render is done (cached)")
        return
    with cluster.connect(workers, scheduler) as client:
        slots = cluster.slots_by_host(client)
        cost = _estimate(client, plans, [r for _, r in todo], nthreads, slots, say)
        threads = sum(s * (nthreads or cluster.render_threads(cluster.cores(), s)) for s in slots.values())
        say(f"benchmark: {len(todo)} renders to do of {sum(len(p.renders()) for p in plans)} "
            f"({len(plans)} jobs); estimated CPU time {cost / 3600:.2f} h, about "
            f"{cost / 3600 / max(threads, 1):.2f} h wall on {threads} render threads"
            + (f"; {len(optimize)} table(s) to optimize first (not in the estimate)" if optimize else ""))
        made = {path: client.submit(_table_task, sp, path, refl, obj, pure=False)
                for path, (sp, refl, obj) in optimize.items()}
        if made:
            # The tables first, all of them: renders that waited on a table's future sat behind
            # hundreds of others on a busy cluster (seen: seven tables never started in an hour).
            with progress.bar(total=len(made), desc="tables", file=sys.stderr, unit="table") as bar:
                for f in as_completed(list(made.values())):
                    f.result()
                    bar.update(1)
        image = [(p, spp) for p in plans for spp, path in p.image_tables.items() if not path.is_file()]
        if image:
            if out is None:
                raise ValueError(f"the {G.IMAGE} row needs the benchmark's folder (out)")
            # Each scene's transfer (and its renders) once, here, before the tables go out to the
            # workers, which then only load it; in the order of the jobs, so that a worker's
            # consecutive tables mostly share the one it keeps.
            for key, (p, _) in {image_transfer_key(p): (p, spp) for p, spp in image}.items():
                image_transfer(p, out, shared, pbrt)
            tasks = [client.submit(_image_task, p, spp, out, shared, pbrt, pure=False) for p, spp in image]
            with progress.bar(total=len(tasks), desc=G.IMAGE, file=sys.stderr, unit="table") as bar:
                for f in as_completed(tasks):
                    f.result()
                    bar.update(1)
        futures = []
        # Whole jobs in order of priority (a run stopped early leaves finished jobs to score),
        # cheap renders first within a job.
        order = {id(p): (priority(p.job), i) for i, p in enumerate(plans)}
        for p, r in sorted(todo, key=lambda pr: (order[id(pr[0])], pr[1].spp * _repeats(pr[1]))):
            futures.append(client.submit(cluster.render_task, r, nthreads, slots, pure=False))
        with progress.bar(total=len(futures), desc="benchmark", file=sys.stderr, unit="render") as bar:
            for f in as_completed(futures):
                f.result()
                bar.update(1)


def priority(job: G.Job) -> int:
    """The order in which jobs are rendered (lower first): the scene sweep's low-discrepancy
    jobs under the compact fluorescent lamp or the scene's own lamps, the lamp sweep's
    ColorChecker, the same scene jobs with independent samples, the rest of the scene sweep,
    the rest of the lamp sweep."""
    headline = job.lamp is None or job.lamp.key == G.HEADLINE_LAMP
    scenes = "scenes" in job.sweep.split("+")
    if scenes and headline:
        return 0 if job.pixel_sampler == "sobol" else 2
    if not scenes and job.scene.key == G.LAMP_SWEEP_SCENES[0]:
        return 1
    if scenes:
        return 3 if job.pixel_sampler == "sobol" else 5
    return 4


def finished(p: JobPlan) -> bool:
    """Every render of the job is there with its inputs unchanged."""
    return all(r.done() is not None for r in p.renders())


def _tables_of(r: RenderJob) -> list[Path]:
    a = r.sampler.args
    return [Path(a[i + 1]) for i, x in enumerate(a) if x == "--wavelength-pdf"]


def _table_ready(r: RenderJob) -> bool:
    return all(t.is_file() for t in _tables_of(r))


def _repeats(r: RenderJob) -> int:
    a = r.sampler.args
    return int(a[a.index("--wavelength-repeats") + 1]) if "--wavelength-repeats" in a else 1


def _estimate(client, plans: Sequence[JobPlan], todo: Sequence[RenderJob], nthreads, slots,
              say: Callable[[str], None]) -> float:
    """CPU seconds of ``todo`` from two short renders of one copy of each scene (on the
    cluster): the copies of a scene differ only in their lamp and pixel sampler, which change
    the cost little, and probing all of them took longer than some sweeps."""
    from wavelength_pdf.evaluation import cluster

    plan_of = {p.scene: p for p in plans}
    wanted = {r.scene for r in todo}
    probe_of: dict[str, JobPlan] = {}
    for p in plans:
        if p.scene in wanted:
            probe_of.setdefault(p.job.scene.key, p)
    probes = {}
    for key, plan in probe_of.items():
        vis = sampler_of(G.BUILTIN, plan.tables)
        probes[key] = [(spp, client.submit(cluster.probe_task,
                                           RenderJob(plan.scene, plan.outdir / "probe" / f"{spp}.exr", vis, spp, 1,
                                                     plan.truth_chunks[0].pbrt),
                                           nthreads, slots, pure=False))
                       for spp in cluster.PROBE_SPP]
    costs = {k: cluster.fit_cost([(spp, *f.result()) for spp, f in runs]) for k, runs in probes.items()}
    by_scene: dict[str, float] = {}
    for r in todo:
        key = plan_of[r.scene].job.scene.key
        by_scene[key] = by_scene.get(key, 0.0) + costs[key].cpu_seconds(r.spp * _repeats(r))
    say("benchmark: estimated CPU minutes by scene: "
        + ", ".join(f"{k} {v / 60:.0f}" for k, v in sorted(by_scene.items(), key=lambda kv: -kv[1])))
    return sum(by_scene.values())


# --- Scoring ---------------------------------------------------------------------------


def _header(path: Path) -> dict:
    from wavelength_pdf.exr import read_header

    h = read_header(path)
    return {"cpu": float(h.get("renderCPUSeconds", np.nan)), "depth": float(h.get("meanPathDepth", np.nan))}


def reference(p: JobPlan):
    """The job's reference from its finished chunks: (image, its two halves, :class:`~.measures.Truth`)."""
    from wavelength_pdf.exr import read_rgb

    chunks = [read_rgb(r.out) for r in p.truth_chunks]
    spp = [r.spp for r in p.truth_chunks]
    image = merge_chunks(chunks, spp)
    halves = merge_chunks(chunks[0::2], spp[0::2]), merge_chunks(chunks[1::2], spp[1::2])
    return image, halves, measures.Truth.of(image, *halves)


def score(p: JobPlan) -> dict:
    """The job's measures (every row and the floor at every spp), its reference's noise and
    every row's bias z-scores; cached in ``scores.json`` by the renders' keys."""
    from wavelength_pdf.exr import read_rgb

    keys = [rendering.render_key(r.scene, r.sampler, r.spp, r.seed, r.pbrt) for r in p.renders()]
    cache = p.outdir / "scores.json"
    key = rendering.file_digest(extra=json.dumps([SCORES_VERSION, keys]))
    if cache.is_file():
        try:
            done = json.loads(cache.read_text())
            if done.get("key") == key:
                return done
        except ValueError:
            pass
    truth_img, halves, truth = reference(p)
    rows = sorted({row for row, _, _ in p.images})
    have = {(row, n) for row, n, _ in p.images} | {(G.FLOOR, n) for n, _ in p.floor}
    out: dict = {"key": key, "job": p.job.name, "scene": p.job.scene.key, "lamp": p.job.lamp_key,
                 "kind": p.job.lamp.kind if p.job.lamp else "own lamps",
                 "spiky": bool(p.job.lamp.spiky) if p.job.lamp else True,
                 "pixel_sampler": p.job.pixel_sampler, "sweep": p.job.sweep,
                 "truth_spp": p.job.truth_spp, "truth_de": truth.de, "truth_de2": truth.de2,
                 "lit_share": float(truth.mask.mean()),
                 "floor_repeats": p.job.floor_repeats, "rows": {}}
    s1, s2 = p.job.seeds
    for row in [*rows, G.FLOOR]:
        per_spp = {}
        for n in p.job.spp:
            if (row, n) not in have:
                continue
            jobs = (p.floor[(n, s1)], p.floor[(n, s2)]) if row == G.FLOOR else (p.images[(row, n, s1)],
                                                                                  p.images[(row, n, s2)])
            a, b = read_rgb(jobs[0].out), read_rgb(jobs[1].out)
            m = measures.pair(a, b, truth)
            h = [_header(j.out) for j in jobs]
            m["mse_rse"] = measures.pair_se(a, b, truth.mask)
            m["bias_z"] = float(np.max(np.abs(measures.bias_z(a, b, truth_img, halves, truth.mask))))
            m["cpu"] = float(np.mean([x["cpu"] for x in h]))
            m["depth"] = float(np.mean([x["depth"] for x in h]))
            per_spp[str(n)] = m
        out["rows"][row] = per_spp
    # The floor keeps 1/K (or less: the K offsets are stratified) of the spd table's
    # wavelength noise; its lower bound subtracts all of that, (K F - E_spd) / (K - 1).
    k = p.job.floor_repeats
    for n, f in out["rows"].get(G.FLOOR, {}).items():
        spd = out["rows"].get(G.FLOOR_TABLE, {}).get(n)
        if spd and k > 1:
            for m in measures.SQUARED:
                f[f"{m}_lo"] = max(0.0, (k * f[m] - spd[m]) / (k - 1))
    rendering.write_json(cache, out)
    return out
