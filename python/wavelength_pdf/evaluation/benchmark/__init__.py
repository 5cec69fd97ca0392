"""The benchmark: every wavelength sampler side by side, as tables (design §6.7, docs/benchmark.md).

- :mod:`.grid`: scenes, lamps, samplers and the two sweeps;
- :mod:`.run`: the scene copies, tables and renders of each job, run resumably on Dask, and
  their scores;
- :mod:`.measures`: error measures that a noisy reference cannot distort (seed pairs), the
  reference's own noise, bias checks, the floor's share, equal-time ratios;
- :mod:`.timing`: CPU seconds per image, one render at a time, alternating samplers;
- :mod:`.report`: the results CSV, the Markdown report and its plots.

:func:`run_benchmark` is the library entry point; ``wavelength-pdf benchmark`` its command.
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import Callable

from wavelength_pdf.evaluation.benchmark import grid as G

__all__ = ["run_benchmark", "G"]

IMAGES = ("error-vs-spp.png", "lamp-sweep.png", "equal-time.png")


def run_benchmark(spec: G.GridSpec, out: Path, *, workers: int | None = None, scheduler: str | None = None,
                  nthreads: int | None = None, pbrt: Path | None = None, timing: bool = False,
                  timing_rounds: int = 5, timing_spp: int = 64, report_spp: int = 64,
                  command: str = "wavelength-pdf benchmark", render: bool = True,
                  say: Callable[[str], None] | None = None) -> list[dict]:
    """Plan every job of ``spec`` under ``out``, render what is missing (``render``), score
    the jobs, optionally time them (``timing``), and write ``results.csv``, ``report.md`` and
    the plots. Returns the flattened result rows."""
    from wavelength_pdf.evaluation.benchmark import report, run
    from wavelength_pdf.evaluation.benchmark import timing as T

    say = say or (lambda msg: print(msg, file=sys.stderr))
    # Absolute: the renders' cache keys hold the tables' paths, which must not depend on how
    # the folder was spelled (-o out/benchmark and -o /abs/out/benchmark are the same grid).
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    for s in spec.skipped:
        say(f"benchmark: skipped {s}")
    if not spec.jobs:
        raise ValueError("benchmark: no job to run (" + ("; ".join(spec.skipped) or "empty selection") + ")")
    say(f"benchmark: planning {len(spec.jobs)} jobs (scene copies and baseline tables)")
    plans = [run.plan_job(job, out, spec.shared, pbrt) for job in spec.jobs]
    if render:
        run.run(plans, workers=workers, scheduler=scheduler, nthreads=nthreads, say=say, out=out,
                shared=spec.shared, pbrt=pbrt)
    else:
        # A grid stopped early: score the finished jobs, name the others.
        done = [p for p in plans if run.finished(p)]
        if len(done) < len(plans):
            kept = {id(p) for p in done}
            say(f"benchmark: {len(plans) - len(done)} of {len(plans)} jobs are not finished and left out of the "
                "report: " + ", ".join(p.job.name for p in plans if id(p) not in kept))
        if not done:
            raise ValueError("benchmark: no job is finished; run without --no-render first")
        plans = done
    scores = [run.score(p) for p in plans]
    rows = report.flatten(scores)
    report.write_csv(out / "results.csv", rows)
    et = []
    if timing:
        path = T.run_timing(T.timing_plans(plans), out, timing_rounds, timing_spp, say)
        et = report.equal_time(rows, T.read_timing(path), timing_spp)
    elif (out / "timing.csv").is_file():
        et = report.equal_time(rows, T.read_timing(out / "timing.csv"), timing_spp)
    spp = report_spp if any(r["spp"] == report_spp for r in rows) else max(r["spp"] for r in rows)
    headline = (f"/{G.HEADLINE_LAMP}/", "/own/")
    scene_jobs = [j for j in report.jobs_of(rows, "scenes", "sobol") if any(h in j for h in headline)] or \
        report.jobs_of(rows, None, "sobol")[:12]
    report.plot_errors(rows, scene_jobs, out / IMAGES[0])
    lamp_jobs = report.jobs_of(rows, "lamps")
    report.plot_lamp_heatmap(rows, lamp_jobs, out / IMAGES[1], spp)
    report.plot_equal_time(et, out / IMAGES[2])
    images = [im for im in IMAGES if (out / im).is_file()]
    report.write_markdown(out / "report.md", rows, scores, et, spp, command, images)
    return rows


def copy_report(out: Path, dest: Path) -> list[Path]:
    """Copy the report, the CSVs and the plots (not renders or tables: the LSPDD spectra and
    tables made from them are not ours to redistribute) to ``dest``."""
    dest.mkdir(parents=True, exist_ok=True)
    copied = []
    for name in ("report.md", "results.csv", "timing.csv", *IMAGES):
        if (out / name).is_file():
            shutil.copyfile(out / name, dest / name)
            copied.append(dest / name)
    return copied
