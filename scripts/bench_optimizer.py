#!/usr/bin/env python3
"""Benchmark the optimizer: J, health and time per spectrum, on one core.

For every spectrum (default: each LSPDD export in ../shared/spectra/lspdd if present, the
CIE illuminants A, D65, FL1-FL12, HP1-HP5, and the cornell-box scene's lamp) this prints

    J of stratified uniform sampling, of the initialization and of the result (at two
    u-resolutions), the result / uniform ratio, the J of the earlier work's table for the
    same lamp where ../shared/tables/reference-4x81 has one, the estimator health, and the
    seconds the optimization took,

then the median seconds per spectrum and how many results meet the acceptance bars of
issue 2 (J <= 10% of uniform, health accepted, J below the reference table's).

The work is restricted to one core per process (CPU affinity plus single-threaded XLA and
BLAS), so the seconds are comparable across machines with different core counts. Use
``--jobs N`` to run N spectra at once (N processes, one core each).

Uses only the package's public interface (spectra, table, objective, optimize).

Examples::

    .venv/bin/python scripts/bench_optimizer.py                  # everything (~minutes)
    .venv/bin/python scripts/bench_optimizer.py cie:FL8 cie:A    # chosen spectra
    .venv/bin/python scripts/bench_optimizer.py --csv bench.csv --tables out/bench/
"""

from __future__ import annotations

import os
import sys


def _one_thread() -> None:
    """Single-threaded XLA and BLAS (must run before JAX starts its backend)."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("MKL_NUM_THREADS", "1")
    flags = os.environ.get("XLA_FLAGS", "")
    if "intra_op_parallelism_threads" not in flags:
        os.environ["XLA_FLAGS"] = (flags + " --xla_cpu_multi_thread_eigen=false"
                                   " intra_op_parallelism_threads=1").strip()


def _one_core(cpu: int = 0) -> None:
    """Single-threaded XLA/BLAS and this process pinned to one CPU (the cpu-th allowed)."""
    _one_thread()
    if hasattr(os, "sched_setaffinity"):
        allowed = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {allowed[(cpu or 0) % len(allowed)]})


if __name__ == "__main__":
    _one_thread()

import argparse  # noqa: E402
import csv  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
LSPDD = SHARED / "spectra" / "lspdd"
REFERENCE = SHARED / "tables" / "reference-4x81"
CORNELL = SHARED / "scenes" / "cornell-box" / "scene-v4.pbrt"

#: Earlier work's tables (../shared/tables/reference-4x81) and the spectrum each was made for.
REFERENCE_FOR = {
    "fluorescent-ipopt": str(CORNELL),
    "A_Std": "cie:A",
    "D65": "cie:D65",
    "FL8": "cie:FL8",
    "sun": str(LSPDD / "2629.csv"),
    "Philips_MH": str(LSPDD / "2641.csv"),
    "Scotopic-2": str(LSPDD / "2639.csv"),
    "Honeybees-2": str(LSPDD / "2689.csv"),
}

COLUMNS = ["spectrum", "name", "J_uniform", "J_init", "J", "J_fine", "ratio", "reference",
           "J_reference", "beats_reference", "bias_rel", "std_rel", "accepted", "solver",
           "seconds", "cpu_seconds", "message"]


def default_specs() -> list[str]:
    specs = [str(p) for p in sorted(LSPDD.glob("*.csv"))] if LSPDD.is_dir() else []
    specs += ["cie:A", "cie:D65"] + [f"cie:FL{i}" for i in range(1, 13)] + \
             [f"cie:HP{i}" for i in range(1, 6)]
    if CORNELL.is_file():
        specs.append(str(CORNELL))
    return specs


def _field(obj, name, default=None):
    return obj.get(name, default) if isinstance(obj, dict) else getattr(obj, name, default)


def run_one(spec: str, args_dict: dict) -> dict:
    """Optimize one spectrum and measure it (runs in the worker process)."""
    import numpy as np

    from wavelength_pdf import objective
    from wavelength_pdf.optimize import optimize_spectrum
    from wavelength_pdf.spectra import load_spectrum
    from wavelength_pdf.table import Table, read_table, write_table

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sp = load_spectrum(spec)
    step = args_dict["grid_step"]
    grid = "auto" if step == "auto" else np.arange(380.0, 780.0 + 1e-9, float(step))
    kwargs = {"grid": grid, "seed": args_dict["seed"], "max_seconds": args_dict["max_seconds"]}
    if args_dict["solver"]:
        kwargs["solver"] = args_dict["solver"]
    t0, c0 = time.perf_counter(), time.process_time()
    res = optimize_spectrum(sp, **kwargs)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    health = _field(res, "health")
    std = np.asarray(_field(health, "std_rel", [np.nan] * 3), dtype=float)
    row = {
        "spectrum": spec, "name": sp.name,
        "J_uniform": float(_field(res, "J_uniform")), "J_init": float(_field(res, "J_init")),
        "J": float(_field(res, "J")), "J_fine": float(_field(res, "J_fine")),
        "bias_rel": float(_field(health, "bias_rel", np.nan)),
        "std_rel": "/".join(f"{v:.3g}" for v in std),
        "accepted": bool(_field(res, "accepted", False)),  # Result.accepted (Health.accepted is a method)
        "solver": str(_field(res, "solver")), "seconds": float(_field(res, "seconds", wall)),
        "cpu_seconds": cpu,
        "message": str(_field(res, "message", "")), "reference": "", "J_reference": "",
        "beats_reference": "",
    }
    row["ratio"] = row["J"] / row["J_uniform"]
    # The earlier work's table for this lamp, evaluated by the same objective.
    for ref, ref_spec in REFERENCE_FOR.items():
        if ref_spec == spec and (REFERENCE / f"{ref}.csv").is_file():
            t = read_table(REFERENCE / f"{ref}.csv")
            problem = objective.make_problem(sp, t.grid)
            j_ref = objective.J(problem, t.pdfs, objective.ORDER_FINE)
            row.update(reference=ref, J_reference=j_ref, beats_reference=row["J_fine"] < j_ref)
    if args_dict["tables"]:
        out = Path(args_dict["tables"])
        out.mkdir(parents=True, exist_ok=True)
        t = _field(res, "table")
        t = t if isinstance(t, Table) else Table(np.asarray(grid), np.asarray(t))
        name = Path(spec).stem if ":" not in spec else spec.replace(":", "-")
        write_table(out / f"{name}.csv", Table(t.grid, t.pdfs, [f"name: {sp.name}",
                                                                 f"source: {spec}",
                                                                 f"J: {row['J']!r}"]))
    return row


def _worker(job: tuple[int, str, dict]) -> dict:
    i, spec, args_dict = job
    try:
        return run_one(spec, args_dict)
    except Exception as e:  # report and go on with the other spectra
        return {"spectrum": spec, "name": "", "message": f"{type(e).__name__}: {e}"}


def _init(cpu_counter) -> None:
    with cpu_counter.get_lock():
        cpu = cpu_counter.value
        cpu_counter.value += 1
    _one_core(cpu)


def _print_row(r: dict) -> None:
    def f(key, fmt):
        v = r.get(key, "")
        return format(v, fmt) if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)

    if not r.get("name"):
        print(f"{r['spectrum'][-34:]:34s}  FAILED: {r.get('message')}", flush=True)
        return
    ref = (f"  ref {r['reference']} {r['J_reference']:.4g} "
           f"{'beaten' if r['beats_reference'] else 'NOT beaten'}") if r.get("reference") else ""
    print(f"{r['name'][:34]:34s} {f('J_uniform', '9.4g')} {f('J_init', '9.4g')} "
          f"{f('J', '9.4g')} {f('J_fine', '9.4g')} {f('ratio', '7.4f')} "
          f"{f('bias_rel', '8.1e')} {r['std_rel']:>20s} {'yes' if r['accepted'] else 'NO ':3s} "
          f"{f('seconds', '7.1f')} {f('cpu_seconds', '7.1f')}{ref}", flush=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("spectra", nargs="*", help="spectra (default: LSPDD + CIE A, D65, FL1-12, "
                                              "HP1-5 + the cornell-box lamp)")
    p.add_argument("--solver", default=None, help="solver name (default: the package default)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--grid-step", default="auto",
                   help="table grid step in nm, or 'auto' (default: the optimizer's line-refined grid)")
    p.add_argument("--max-seconds", type=float, default=None, help="time budget per spectrum")
    p.add_argument("--jobs", type=int, default=1, help="spectra at once, one core each")
    p.add_argument("--csv", default=None, help="also write the rows to this CSV file")
    p.add_argument("--tables", default=None, help="also write each result table to this folder")
    args = p.parse_args(argv)

    specs = args.spectra or default_specs()
    args_dict = {"solver": args.solver, "seed": args.seed, "grid_step": args.grid_step,
                 "max_seconds": args.max_seconds, "tables": args.tables}
    print(f"{len(specs)} spectra, {args.jobs} process(es) with one core and one XLA thread each")
    print(f"{'spectrum':34s} {'J unif':>9s} {'J init':>9s} {'J':>9s} {'J fine':>9s} "
          f"{'J/unif':>7s} {'bias':>8s} {'std/c X/Y/Z':>20s} ok  {'seconds':>7s} {'cpu s':>7s}")
    rows: list[dict] = []
    jobs = [(i, s, args_dict) for i, s in enumerate(specs)]
    if args.jobs <= 1:
        _one_core(0)
        for job in jobs:
            rows.append(_worker(job))
            _print_row(rows[-1])
    else:
        import concurrent.futures as cf
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")  # JAX is not fork-safe
        counter = ctx.Value("i", 0)
        with cf.ProcessPoolExecutor(args.jobs, mp_context=ctx, initializer=_init,
                                    initargs=(counter,)) as pool:
            for row in pool.map(_worker, jobs):
                rows.append(row)
                _print_row(row)

    ok = [r for r in rows if r.get("name")]
    if ok:
        secs = [r["seconds"] for r in ok]
        cpus = [r["cpu_seconds"] for r in ok]
        print()
        print(f"median seconds per spectrum (one core): {statistics.median(secs):.1f} wall "
              f"(min {min(secs):.1f}, max {max(secs):.1f}, total {sum(secs):.0f}); "
              f"{statistics.median(cpus):.1f} CPU (the wall time on an otherwise idle core)")
        print(f"accepted: {sum(r['accepted'] for r in ok)}/{len(ok)}; "
              f"J <= 0.1 x uniform: {sum(r['ratio'] <= 0.1 for r in ok)}/{len(ok)}; "
              f"median J/uniform {statistics.median(r['ratio'] for r in ok):.4f}")
        refs = [r for r in ok if r.get("reference")]
        if refs:
            print(f"beats the reference table: {sum(bool(r['beats_reference']) for r in refs)}"
                  f"/{len(refs)} (" + ", ".join(
                      f"{r['reference']} {r['J_fine'] / r['J_reference']:.3f}x" for r in refs) + ")")
    if len(ok) < len(rows):
        print(f"{len(rows) - len(ok)} spectra failed")
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
            w.writeheader()
            w.writerows(rows)
    return 0 if len(ok) == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
