"""Running an evaluation grid's renders on a Dask cluster (``dask.distributed``).

Every render of every job (:class:`~.protocol.RenderJob`: ground-truth chunks and compared
images) is one task; a job's table optimization is a task that its table renders wait for, and
the merge of a truth's chunks is a task that waits for the chunks. A task only reads and writes
files, under the grid's output folder: tasks are idempotent (a render whose inputs are unchanged
is reused, and files are renamed into place), so a task that Dask retries after its worker died,
or a grid resumed on another machine, redoes no finished render.

Workers therefore see the same files at the same paths as the client: the output folder, the
renderer binary, the scenes (with their meshes and textures) on a shared filesystem; spectra
travel with the tasks. Each worker needs this package installed (``pip install`` of the
repository, which brings ``distributed``) and the same renderer build at the same path.

- :func:`connect`: a local cluster (``--workers N``) or an existing one (``--scheduler``).
- :func:`render_threads`: how many threads a render on a worker uses.
- :func:`estimate` / :func:`probe`: the CPU time the remaining renders will take.
- :func:`run`: submit all the plans' tasks, follow them with a progress bar, collect images.
"""
from __future__ import annotations

import contextlib
import os
import sys
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Sequence

from wavelength_pdf import progress

from wavelength_pdf.evaluation import render as rendering
from wavelength_pdf.evaluation.protocol import Plan, RenderJob, ensure_table, merge_truth
from wavelength_pdf.spectra import Spectrum

#: The probe's sample counts: two renders separate start-up time from time per sample.
PROBE_SPP = (1, 8)


def cores() -> int:
    """The CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def connect(workers: int | None = None, scheduler: str | None = None) -> Iterator:
    """A ``distributed.Client``: of the cluster at ``scheduler`` (``tcp://HOST:PORT``), or of a
    local cluster of ``workers`` single-threaded worker processes (default: one per core)."""
    from distributed import Client, LocalCluster

    if scheduler:
        with Client(scheduler, timeout="30s") as client:
            yield client
        return
    n = workers or cores()
    if n < 1:
        raise ValueError(f"--workers must be at least 1, got {n}")
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None) as lc, \
            Client(lc) as client:
        yield client


def slots_by_host(client) -> dict[str, int]:
    """How many tasks the cluster runs at once on each host (the workers' threads summed)."""
    from distributed.comm import get_address_host

    slots: Counter = Counter()
    for address, info in client.scheduler_info(n_workers=-1)["workers"].items():
        slots[get_address_host(address)] += int(info.get("nthreads", 1))
    return dict(slots)


def render_threads(host_cores: int, host_slots: int) -> int:
    """Renderer threads for one render on a host running ``host_slots`` tasks at once: the
    host's cores shared out, so that tasks x threads = cores (at least one thread)."""
    return max(1, host_cores // max(1, host_slots))


def _threads_here(nthreads: int | None, slots: dict[str, int]) -> int:
    """A task's render threads: ``nthreads`` if given, else this host's share of its cores."""
    if nthreads:
        return nthreads
    from distributed import get_worker
    from distributed.comm import get_address_host

    worker = get_worker()
    host_slots = slots.get(get_address_host(worker.address), worker.state.nthreads)
    return render_threads(cores(), host_slots)


def render_task(job: RenderJob, nthreads: int | None, slots: dict[str, int], *after) -> rendering.Render:
    """A render on a worker (``after``: futures it waits for, e.g. its table)."""
    return job.run(_threads_here(nthreads, slots))


def table_task(spectrum: Spectrum, path: Path, lo: float, hi: float, reflectances=None,
               objective: str = "J") -> Path:
    """Optimize a job's table unless it is there, under a temporary name renamed into place
    (a task retried after its worker died never finds half a table)."""
    path = Path(path)
    if path.is_file():
        return ensure_table(spectrum, path, lo, hi, reflectances=reflectances, objective=objective)
    tmp = rendering.temporary(path)
    try:
        ensure_table(spectrum, tmp, lo, hi, reflectances=reflectances, objective=objective)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def merge_task(jobs: Sequence[RenderJob], out: Path, *chunks: rendering.Render) -> rendering.Render:
    return merge_truth(list(chunks), list(jobs), out)


def probe_task(job: RenderJob, nthreads: int | None, slots: dict[str, int]) -> tuple[int, float]:
    """Render ``job`` uncached; its render threads and wall seconds."""
    threads = _threads_here(nthreads, slots)
    r = rendering.render(job.scene, job.out, job.sampler, job.spp, seed=job.seed, nthreads=threads,
                         pbrt=job.pbrt, cache=False)
    return threads, r.seconds


@dataclass(frozen=True)
class Cost:
    """A scene's measured render cost: wall seconds = ``start`` + ``per_spp`` x spp, on ``threads``."""

    start: float
    per_spp: float
    threads: int

    def cpu_seconds(self, spp: int) -> float:
        # Start-up (parsing, building the BVH) is mostly one thread; sampling uses them all.
        return self.start + self.per_spp * spp * self.threads


def fit_cost(probes: Sequence[tuple[int, int, float]]) -> Cost:
    """A :class:`Cost` from (spp, threads, seconds) probe renders of one scene (two spp)."""
    (s1, t1, w1), (s2, _, w2) = sorted(probes)[:1] + sorted(probes)[-1:]
    per = max((w2 - w1) / (s2 - s1), 0.0) if s2 > s1 else 0.0
    return Cost(max(w1 - per * s1, 0.0), per, t1)


def todo(plans: Sequence[Plan]) -> list[RenderJob]:
    """The renders not finished yet (cached ones with unchanged inputs are left out)."""
    return [j for p in plans for j in [*p.truth_chunks, *p.images.values()] if j.done() is None]


def probe(client, plans: Sequence[Plan], nthreads: int | None, slots: dict[str, int]) -> dict[str, Cost]:
    """Two short uniform-sampling renders per scene of the plans, on the cluster, timed."""
    from wavelength_pdf.evaluation.render import samplers

    futures: dict[str, list] = {}
    for p in plans:
        if p.name in futures:
            continue
        uniform = samplers(None, p.config.lo, p.config.hi)["uniform"]
        for spp in PROBE_SPP:
            job = RenderJob(p.scene, p.outdir.parent / "probe" / f"{p.name}-{spp}.exr", uniform, spp, 1,
                            p.config.pbrt)
            futures.setdefault(p.name, []).append(
                (spp, client.submit(probe_task, job, nthreads, slots, pure=False)))
    return {name: fit_cost([(spp, *f.result()) for spp, f in runs]) for name, runs in futures.items()}


def estimate(jobs: Sequence[RenderJob], plans: Sequence[Plan], costs: dict[str, Cost]) -> float:
    """CPU seconds of ``jobs`` from their scenes' probe costs."""
    name = {p.scene: p.name for p in plans}
    return sum(costs[name[j.scene]].cpu_seconds(j.spp) for j in jobs)


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.2f} h" if seconds >= 360 else f"{seconds / 60:.1f} min"


def run(client, plans: Sequence[Plan], optimize: dict[Path, Spectrum], nthreads: int | None = None,
        label: str = "grid", say=None):
    """Run every plan's renders on ``client``'s cluster.

    ``optimize``: the tables to optimize first (a task each; the renders with a table wait for
    its task), by path, with their spectra (or (spectrum, reflectance set) pairs). Returns, per plan, the
    truth's :class:`~.render.Render` and the images by (method, spp, seed). Before submitting,
    prints the estimated CPU time of the renders still to do (from :func:`probe`); a progress
    bar follows every render."""
    from distributed import as_completed

    say = say or (lambda msg: print(msg, file=sys.stderr))
    from distributed.comm import get_address_host

    slots = slots_by_host(client)
    host_cores = {get_address_host(a): n for a, n in client.run(cores).items()}
    remaining = todo(plans)
    total = sum(len(p.truth_chunks) + len(p.images) for p in plans)
    if remaining:
        cpu = estimate(remaining, plans, probe(client, plans, nthreads, slots))
        threads = sum(s * (nthreads or render_threads(host_cores.get(h, 1), s)) for h, s in slots.items())
        wall = f", about {_hours(cpu / threads)} wall with {threads} render threads at once"
        missing = sum(1 for t in optimize if not Path(t).is_file())
        say(f"{label}: {len(remaining)} of {total} renders to do ({total - len(remaining)} cached); "
            f"estimated CPU time {_hours(cpu)}{wall} on {sum(slots.values())} worker slots"
            + (f"; {missing} table(s) to optimize first, not in the estimate" if missing else ""))
    lo_hi = {p.table: (p.config.lo, p.config.hi) for p in plans}
    # A table's entry is its spectrum, or (spectrum, reflectance set) for surface colours.
    made = {Path(t): client.submit(table_task, *(sp if isinstance(sp, tuple) else (sp,))[:1], Path(t),
                                   *lo_hi[Path(t)], *(sp[1:] if isinstance(sp, tuple) else ()), pure=False)
            for t, sp in optimize.items()}
    watched, names, truths, images = [], {}, [], []
    for p in plans:
        def submit(job: RenderJob, what: str):
            deps = [made[p.table]] if job.sampler.name == "table" and p.table in made else []
            f = client.submit(render_task, job, nthreads, slots, *deps, pure=False)
            watched.append(f)
            names[f.key] = f"{p.name}/{p.illuminant}: {what}"
            return f

        chunks = [submit(job, f"truth {job.spp} spp seed {job.seed}") for job in p.truth_chunks]
        truths.append(client.submit(merge_task, p.truth_chunks, p.truth, *chunks, pure=False))
        images.append({key: submit(job, f"{key[0]} {key[1]} spp seed {key[2]}") for key, job in p.images.items()})
    with progress.bar(total=total, desc=label, file=sys.stderr, unit="render") as bar:
        for f in as_completed(watched):
            f.result()  # a failed render raises its RenderError here
            bar.set_postfix_str(names.get(f.key, ""), refresh=False)
            bar.update(1)
    out = [(t.result(), {key: f.result() for key, f in im.items()}) for t, im in zip(truths, images)]
    for p in plans:  # every task is done: a temporary file idle for a while is an orphan
        sweep(p.outdir / "renders", time.time() - 10.0)
    return out


def sweep(folder: Path, before: float) -> list[Path]:
    """Remove the temporary files that renders killed with their worker left in ``folder``
    (those last written before ``before``, so that one still being written stays)."""
    gone = []
    for f in Path(folder).glob(".*.tmp.*"):
        with contextlib.suppress(OSError):
            if f.stat().st_mtime < before:
                f.unlink()
                gone.append(f)
    return gone
