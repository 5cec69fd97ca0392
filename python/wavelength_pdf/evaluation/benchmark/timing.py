"""CPU time per image, measured one render at a time, alternating the samplers (design §6.7).

The grid's renders run side by side on a cluster, so their times say little about cost. This
phase renders each timing job's rows one at a time on one thread, in a rotated order in every
round (A B C, B C A, C A B, ...), so that a drift of the machine's speed is shared out; it records
the process's CPU seconds (user + system, from the operating system), the render loop's CPU
seconds and mean path depth (the image's ``renderCPUSeconds`` and ``meanPathDepth``), and the
machine's load average when the phase starts. Run it on an idle machine.
"""
from __future__ import annotations

import csv
import os
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from wavelength_pdf.evaluation import render as rendering
from wavelength_pdf.evaluation.benchmark import grid as G
from wavelength_pdf.evaluation.benchmark.run import JobPlan, sampler_of
from wavelength_pdf.renderer import find_pbrt

FIELDS = ["job", "row", "round", "spp", "process_cpu", "render_cpu", "wall", "depth"]


def timing_plans(plans: Sequence[JobPlan]) -> list[JobPlan]:
    """The jobs timed by default: every scene once, low-discrepancy pixel sampler, under the
    headline lamp (``grid.HEADLINE_LAMP``, or its own lamps), else the first lamp it has."""
    chosen: dict[str, JobPlan] = {}
    for p in plans:
        if p.job.pixel_sampler != "sobol":
            continue
        prefer = p.job.lamp is None or p.job.lamp.key == G.HEADLINE_LAMP
        have = chosen.get(p.job.scene.key)
        if have is None or (prefer and have.job.lamp_key not in ("own", G.HEADLINE_LAMP)):
            chosen[p.job.scene.key] = p
    return list(chosen.values())


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def time_job(p: JobPlan, rounds: int, spp: int, out: Path, say: Callable[[str], None]) -> list[dict]:
    """``rounds`` renders of every row of ``p`` (one thread each, rotated order); rows as dicts."""
    from wavelength_pdf.exr import read_header

    rows = [r for r in sorted({row for row, _, _ in p.images}) if r != G.FLOOR]
    pbrt = find_pbrt(p.truth_chunks[0].pbrt)
    out.mkdir(parents=True, exist_ok=True)
    records = []
    for k in range(rounds):
        order = rows[k % len(rows):] + rows[:k % len(rows)]
        for row in order:
            img = out / f"{row}.exr"
            cmd = [str(pbrt), "--quiet", "--nthreads", "1", "--spp", str(spp), "--seed", str(1 + k),
                   *sampler_of(row, p.tables_at(spp), net=p.job.wavelength_net).args, "--outfile", str(img), str(p.scene)]
            c0, w0 = _cpu_children(), time.perf_counter()
            proc = subprocess.run(cmd, capture_output=True, text=True)
            wall, cpu = time.perf_counter() - w0, _cpu_children() - c0
            if proc.returncode != 0:
                raise rendering.RenderError(f"{' '.join(cmd)} failed:\n{proc.stderr.strip()}")
            h = read_header(img)
            records.append({"job": p.job.name, "row": row, "round": k, "spp": spp, "process_cpu": cpu,
                            "render_cpu": float(h.get("renderCPUSeconds", np.nan)), "wall": wall,
                            "depth": float(h.get("meanPathDepth", np.nan))})
        say(f"timing {p.job.name}: round {k + 1} of {rounds}")
    return records


def run_timing(plans: Sequence[JobPlan], out: Path, rounds: int = 5, spp: int = 64,
               say: Callable[[str], None] | None = None) -> Path:
    """Time the jobs (resumable: a job already in ``timing.csv`` with as many rounds and the
    same spp is kept); returns the CSV's path."""
    say = say or (lambda msg: print(msg, file=sys.stderr))
    path = out / "timing.csv"
    done: list[dict] = []
    if path.is_file():
        with open(path, newline="") as f:
            done = list(csv.DictReader(f))
    load = os.getloadavg()[0]
    say(f"timing: load average {load:.2f} over the last minute "
        + ("(the machine is not idle: these times are not a result)" if load > 0.5 else "(idle)"))
    for p in plans:
        have = [r for r in done if r["job"] == p.job.name and int(r["spp"]) == spp]
        if len({r["round"] for r in have}) >= rounds:
            continue
        done = [r for r in done if r["job"] != p.job.name]
        done += time_job(p, rounds, spp, out / "timing" / p.job.name.replace("/", "-"), say)
        tmp = rendering.temporary(path)
        with open(tmp, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=FIELDS)
            w.writeheader()
            w.writerows(done)
        os.replace(tmp, path)
    return path


def read_timing(path: Path) -> dict[tuple[str, str], dict[str, float]]:
    """Per (job, row): the median, minimum and maximum render CPU seconds, the median process
    CPU seconds, the median path depth and the number of runs."""
    if not Path(path).is_file():
        return {}
    with open(path, newline="") as f:
        recs = list(csv.DictReader(f))
    out: dict[tuple[str, str], dict[str, float]] = {}
    for key in sorted({(r["job"], r["row"]) for r in recs}):
        rs = [r for r in recs if (r["job"], r["row"]) == key]
        cpu = np.array([float(r["render_cpu"]) for r in rs])
        out[key] = {"cpu": float(np.median(cpu)), "cpu_min": float(cpu.min()), "cpu_max": float(cpu.max()),
                    "process_cpu": float(np.median([float(r["process_cpu"]) for r in rs])),
                    "depth": float(np.median([float(r["depth"]) for r in rs])), "runs": len(rs),
                    "spp": int(rs[0]["spp"])}
    return out
