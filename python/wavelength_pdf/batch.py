"""Every spectrum file of a folder to a table each, plus ``summary.csv``: parallel, resumable.

The library side of ``wavelength-pdf batch``: :func:`plan_batch` lists the work,
:func:`run_batch` keeps tables newer than their input, optimizes the rest (in worker
processes when asked) and writes the summary, one :meth:`Result.summary_row` per input.
"""
from __future__ import annotations

import concurrent.futures as cf
import csv
import ctypes
import multiprocessing
import os
import signal
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from wavelength_pdf.coverage import check_range
from wavelength_pdf.problem import DEFAULT_OBJECTIVE_SPP, objective_label
from wavelength_pdf.produce import optimize_one
from wavelength_pdf.result import SUMMARY_FIELDS, Result
from wavelength_pdf.spectra import SpectrumError, load_spectra
from wavelength_pdf.table import TableError, read_table

#: File types ``batch`` picks up in a folder.
SPECTRUM_SUFFIXES = (".csv", ".spd", ".pbrt")


class BatchError(ValueError):
    """A folder that cannot be batched (not a folder, no spectrum files)."""


@dataclass
class Item:
    """One spectrum of the batch: its spec, the file it comes from and its table."""

    spec: str
    source: Path
    out: Path


def _row(input_: str, status: str, message: str = "", result: Result | None = None,
         table: str = "") -> dict[str, Any]:
    if result is not None:
        return result.summary_row(input_, table, status, message)
    row = {k: "" for k in SUMMARY_FIELDS}
    row.update(input=input_, table=table, status=status, message=message)
    return row


def plan_batch(folder: Path, outdir: Path, lo: float, hi: float) -> tuple[list[Item], list[dict]]:
    """An :class:`Item` for every spectrum in ``folder``, and summary rows for bad inputs.

    A scene with several emitter spectra gives one item per emitter (``scene.pbrt#i``),
    its tables named ``<stem>-<i>.csv``.
    """
    folder, outdir = Path(folder), Path(outdir)
    if not folder.is_dir():
        raise BatchError(f"{folder}: not a folder")
    items: list[Item] = []
    errors: list[dict] = []
    files = sorted(p for p in folder.iterdir()
                   if p.is_file() and p.suffix.lower() in SPECTRUM_SUFFIXES)
    for f in files:
        if f.suffix.lower() == ".pbrt":
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    n = len(load_spectra(str(f), lo=lo, hi=hi))
            except SpectrumError as e:
                errors.append(_row(str(f), "error", str(e)))
                continue
            if n == 1:
                items.append(Item(str(f), f, outdir / f"{f.stem}.csv"))
            else:
                items += [Item(f"{f}#{i}", f, outdir / f"{f.stem}-{i}.csv") for i in range(n)]
        else:
            items.append(Item(str(f), f, outdir / f"{f.stem}.csv"))
    return items, errors


def run_job(job: dict[str, Any]) -> dict[str, Any]:
    """One item, in this process or a worker: optimize, write, return its summary row."""
    spec, out = job["spec"], Path(job["out"])
    try:
        lo, hi = job["range"]
        sp = load_spectra(spec, lo=lo, hi=hi)
        if len(sp) != 1:
            raise SpectrumError(f"{spec}: expected one spectrum, got {len(sp)}")
        check_range(sp[0], lo, hi)  # light beyond the table's ends (design §3.3)
        grid = job["grid"] if isinstance(job["grid"], str) else np.asarray(job["grid"])
        o = optimize_one(sp[0], out, grid, job["solver"], job["seed"], job["max_seconds"], None,
                         max_evals=job.get("max_evals"), objective=job.get("objective", "J"),
                         objective_spp=job.get("objective_spp"), reflectances=job.get("reflectances"))
        if o.written:
            return _row(spec, "written", "", o.result, str(out))
        return _row(spec, "not accepted", o.result.reason, o.result)
    except (SpectrumError, TableError, OSError, ValueError) as e:
        return _row(spec, "error", str(e))


def _init_worker(parent: int) -> None:
    """A worker's BLAS threads: one (several workers share the cores). XLA's thread count
    comes with the parent's environment (``PJRT_NPROC``, :mod:`wavelength_pdf.threads`).
    And the worker dies with ``parent`` (:func:`_die_with_parent`)."""
    os.environ["OMP_NUM_THREADS"] = "1"
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    _die_with_parent(parent)


#: prctl(2) option: the signal the kernel sends this process when its parent ends.
_PR_SET_PDEATHSIG = 1


def _die_with_parent(parent: int) -> None:
    """End this worker when ``parent`` (the batch process) ends, however it ends.

    A worker busy optimizing (60-90 s, ~380 MB) does not look at its pipe to the parent, so
    a parent killed by SIGKILL or SIGTERM (no cleanup runs) used to leave it running to the
    end of its job. On Linux the kernel sends it SIGTERM when the parent ends
    (``PR_SET_PDEATHSIG``; the parent starts its workers from its main thread, which lives as
    long as it does); a parent that ended before the request was made is seen by the parent
    pid having changed. Elsewhere the parent's own cleanup (:func:`_stop_workers`) is all.
    """
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os._exit(1)


def _stop_workers(pool: cf.ProcessPoolExecutor) -> None:
    """Cancel what has not started and end the running workers now, instead of waiting for
    their jobs (an interrupted batch: Ctrl-C, or an error in the parent)."""
    # The executor has no public way to stop a running job, and shutdown() forgets its
    # processes: take them first.
    procs = list((getattr(pool, "_processes", None) or {}).values())
    for proc in procs:
        try:
            proc.terminate()
        except (OSError, ValueError):
            pass
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        try:
            proc.join(timeout=5)
        except (OSError, ValueError, AssertionError):
            pass


def run_batch(folder: Path, outdir: Path, *, lo: float, hi: float, grid: np.ndarray | str,
              solver: str | None, seed: int, max_seconds: float | None = None,
              max_evals: int | None = None, objective: str = "J", objective_spp: int | None = None,
              reflectances=None, jobs: int = 1, force: bool = False,
              on_start: Callable[[int], None] | None = None,
              on_row: Callable[[dict], None] | None = None) -> tuple[list[dict], Path]:
    """Optimize every spectrum of ``folder`` into ``outdir``; returns the rows and summary.csv.

    Resumable: a table newer than its input, for the same objective (design §4.6) and surface
    colours (``reflectances``, a :class:`~wavelength_pdf.reflectances.ReflectanceSet` or None
    for the white surface; design §4.5), is kept and its header fills its row (status
    ``kept``), unless ``force``. ``on_start(n)`` is told how many items will be optimized,
    ``on_row(row)`` gets each finished row.
    """
    from wavelength_pdf.reflectances import colours_label

    folder, outdir = Path(folder), Path(outdir)
    items, rows = plan_batch(folder, outdir, lo, hi)
    if not items and not rows:
        raise BatchError(f"{folder}: no spectrum files ({', '.join(SPECTRUM_SUFFIXES)})")
    outdir.mkdir(parents=True, exist_ok=True)
    wanted = objective_label(objective, DEFAULT_OBJECTIVE_SPP if objective_spp is None else objective_spp)
    # A table older than the reflectance file it was made for is redone too.
    colours_file = Path(reflectances.source) if reflectances is not None else None
    colours_time = colours_file.stat().st_mtime if colours_file is not None and colours_file.is_file() else 0.0
    todo: list[dict[str, Any]] = []
    for it in items:
        if (not force and it.out.is_file()
                and it.out.stat().st_mtime >= max(it.source.stat().st_mtime, colours_time)):
            try:
                kept = Result.from_table(read_table(it.out))
                if kept.objective != wanted:
                    raise TableError(f"made for the objective {kept.objective!r}")
                if kept.source.partition("; reflectances: ")[2] != colours_label(reflectances):
                    raise TableError("made for other surface colours")
                rows.append(_row(it.spec, "kept", "table newer than input", kept, str(it.out)))
                continue
            except TableError:
                pass  # unreadable, or for another objective: redo it
        todo.append({"spec": it.spec, "out": str(it.out), "range": (lo, hi),
                     "grid": grid if isinstance(grid, str) else np.asarray(grid).tolist(),
                     "solver": solver, "seed": seed, "max_seconds": max_seconds,
                     "max_evals": max_evals, "objective": objective, "objective_spp": objective_spp,
                     "reflectances": reflectances})
    if on_start is not None:
        on_start(len(todo))
    report = on_row or (lambda row: None)
    if jobs <= 1 or len(todo) <= 1:
        for job in todo:
            rows.append(run_job(job))
            report(rows[-1])
    else:
        # JAX is not fork-safe: workers are spawned (and inherit PJRT_NPROC).
        ctx = multiprocessing.get_context("spawn")
        # Not a with-block: its exit would wait for the executor again after an interrupt,
        # when the workers are already being stopped.
        pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_init_worker,
                                      initargs=(os.getpid(),))
        try:
            for fut in cf.as_completed([pool.submit(run_job, job) for job in todo]):
                rows.append(fut.result())
                report(rows[-1])
        except BaseException:
            _stop_workers(pool)
            raise
        pool.shutdown(wait=True)
    rows.sort(key=lambda r: r["input"])
    summary = outdir / "summary.csv"
    tmp = summary.with_name(f".{summary.name}.tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=SUMMARY_FIELDS)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, summary)
    return rows, summary
