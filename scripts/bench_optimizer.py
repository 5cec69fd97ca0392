#!/usr/bin/env python3
"""Benchmark the optimizer: J ratio, health and whole-process seconds per spectrum.

Every spectrum is optimized by its own ``wavelength-pdf optimize SPECTRUM -o TABLE``
process, as a user runs it (start-up, imports, spectrum reading, compilation or the
persistent compilation cache, the optimization, writing the table), pinned to one core
with one XLA thread. For each it prints J of stratified uniform sampling, of the
initialization and of the result (at two u-resolutions, design §4), the ratio
J / J_uniform, the health figures and whether the table is accepted, the table's node
count, and the process's wall and CPU seconds (``resource.getrusage`` of the child: on a
shared machine the CPU seconds are what an otherwise idle core would take). Then the
median and the worst of the seconds and of the ratio, and how many spectra meet the bar
``--bar`` (default 0.05 x uniform, accepted).

The default list: the LSPDD exports in ../shared/spectra/lspdd (skipped when absent),
every illuminant and light source colour-science ships (``colour.SDS_ILLUMINANTS`` as
``cie:NAME``, ``colour.SDS_LIGHT_SOURCES`` as ``lamp:NAME``) and synthetic line spectra
written here (``synthetic:NAME``: Gaussian lines of 0.1-2 nm, laser triplets, lines on a
weak continuum, a line partly outside the range), and the 4 x 81 tables of Dobos 2025
(../shared/tables/reference-4x81) scored against the same lamps.

Examples::

    taskset -c 0 .venv/bin/python scripts/bench_optimizer.py             # everything
    .venv/bin/python scripts/bench_optimizer.py cie:FL8 synthetic:line-0.2nm
    .venv/bin/python scripts/bench_optimizer.py --list                   # the default list
    .venv/bin/python scripts/bench_optimizer.py --csv bench.csv --tables out/bench/
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
LSPDD = SHARED / "spectra" / "lspdd"
REFERENCE = SHARED / "tables" / "reference-4x81"
CORNELL = SHARED / "scenes" / "cornell-box" / "scene-v4.pbrt"

#: The 4 x 81 tables of Dobos 2025 (../shared/tables/reference-4x81) and the spectrum each was made for.
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

COLUMNS = ["spectrum", "name", "nodes", "J_uniform", "J_init", "J", "J_fine", "ratio", "bias_rel",
           "std_rel", "accepted", "seconds", "cpu_seconds", "reference", "J_reference", "message"]


# --- Synthetic line spectra -----------------------------------------------------------

#: Fine wavelength list of the synthetic spectra, nm (beyond the 380-780 range).
_FINE_STEP = 0.01


def _gauss(wl, centre, fwhm):
    sigma = fwhm / (2.0 * math.sqrt(2.0 * math.log(2.0)))
    import numpy as np

    return np.exp(-0.5 * ((wl - centre) / sigma) ** 2)


def synthetic(name: str):
    """(wavelengths, values) of the synthetic spectrum ``name`` (see ``SYNTHETIC``)."""
    import numpy as np

    wl = np.round(np.arange(360.0, 830.0 + 1e-9, _FINE_STEP), 6)
    g = lambda c, w: _gauss(wl, c, w)  # noqa: E731
    if name.startswith("line-"):
        return wl, g(532.0, float(name[5:-2]))
    if name == "laser-triplet-0.5nm":
        return wl, g(457.0, 0.5) + g(532.0, 0.5) + 0.8 * g(635.0, 0.5)
    if name == "mercury-lines-0.6nm":
        lines = ((404.7, 0.3), (435.8, 1.0), (546.1, 0.9), (577.0, 0.25), (579.1, 0.25))
        return wl, 0.01 + sum(a * g(c, 0.6) for c, a in lines)
    if name == "box-line-0.3nm":
        return wl, ((wl >= 589.0) & (wl <= 589.3)).astype(float)
    if name == "edge-line-1nm":
        return wl, g(380.3, 1.0) + 0.5 * g(610.0, 1.0)
    raise KeyError(name)


SYNTHETIC = ["line-0.1nm", "line-0.2nm", "line-0.5nm", "line-2nm", "laser-triplet-0.5nm",
             "mercury-lines-0.6nm", "box-line-0.3nm", "edge-line-1nm"]


def write_spd(path: Path, wl, values) -> None:
    """A pbrt ``.spd`` file (``lambda value`` per line)."""
    with open(path, "w") as fh:
        for x, v in zip(wl, values):
            fh.write(f"{x:.6f} {v:.17g}\n")


# --- The list -------------------------------------------------------------------------


def default_specs() -> list[str]:
    specs = [str(p) for p in sorted(LSPDD.glob("*.csv"))] if LSPDD.is_dir() else []
    import colour

    specs += [f"cie:{k}" for k in colour.SDS_ILLUMINANTS]
    specs += [f"lamp:{k}" for k in colour.SDS_LIGHT_SOURCES]
    specs += [f"synthetic:{k}" for k in SYNTHETIC]
    return specs


# --- One spectrum, one process --------------------------------------------------------


def _cli() -> list[str]:
    exe = Path(sys.executable).with_name("wavelength-pdf")
    return [str(exe)] if exe.is_file() else [sys.executable, "-m", "wavelength_pdf.cli"]


def _child_env() -> dict:
    env = dict(os.environ)
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    flags = env.get("XLA_FLAGS", "")
    if "intra_op_parallelism_threads" not in flags:
        env["XLA_FLAGS"] = (flags + " --xla_cpu_multi_thread_eigen=false"
                            " intra_op_parallelism_threads=1").strip()
    return env


def _header(path: Path) -> dict:
    out = {}
    with open(path) as fh:
        for line in fh:
            if not line.startswith("#"):
                break
            key, sep, value = line[1:].partition(":")
            if sep:
                out.setdefault(key.strip(), value.strip())
    return out


def _float(s, default=float("nan")) -> float:
    try:
        return float(s)
    except (TypeError, ValueError):
        return default


def run_one(spec: str, tmp: Path, extra: list[str], tables: Path | None) -> dict:
    """Run ``wavelength-pdf optimize`` on ``spec`` in a child process and measure it."""
    arg = spec
    if spec.startswith("synthetic:"):
        arg = str(tmp / f"{spec[10:]}.spd")
        write_spd(Path(arg), *synthetic(spec[10:]))
    out = tmp / "table.csv"
    out.unlink(missing_ok=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(_cli() + ["optimize", arg, "-o", str(out), *extra],
                          capture_output=True, text=True, env=_child_env())
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    row = {"spectrum": spec, "seconds": wall, "cpu_seconds": cpu, "accepted": False,
           "message": (proc.stdout.strip().splitlines() or [""])[-1][-160:]}
    if out.is_file():
        h = _header(out)
        with open(out) as fh:
            nodes = sum(1 for line in fh if line[:1].isdigit())
        row.update(name=h.get("name", ""), nodes=nodes, J_uniform=_float(h.get("J_uniform")),
                   J_init=_float(h.get("J_init")), J=_float(h.get("J")),
                   J_fine=_float(h.get("J_fine")), bias_rel=_float(h.get("bias_rel")),
                   std_rel=h.get("std_rel", ""), accepted=h.get("accepted") == "True",
                   message=h.get("message", ""))
        row["ratio"] = row["J"] / row["J_uniform"]
        if tables is not None:
            tables.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(out, tables / (re.sub(r"[^\w.+-]+", "_", spec).strip("_") + ".csv"))
    else:
        # Not accepted (no table is written) or failed: the summary line has the ratio.
        m = re.search(r"= ([0-9.eE+-]+) x uniform", proc.stdout)
        row.update(name=spec, ratio=_float(m[1]) if m else float("nan"),
                   message=(proc.stdout + proc.stderr).strip()[-300:] or f"exit {proc.returncode}")
    return row


def score_references(rows: list[dict], tmp: Path) -> None:
    """J of the Dobos 2025 table for the same lamp, by the project's evaluator."""
    by_spec = {r["spectrum"]: r for r in rows}
    todo = [(ref, spec) for ref, spec in REFERENCE_FOR.items()
            if spec in by_spec and (REFERENCE / f"{ref}.csv").is_file()]
    if not todo:
        return
    from wavelength_pdf.optimize import evaluate_table
    from wavelength_pdf.spectra import load_spectrum
    from wavelength_pdf.table import read_table

    for ref, spec in todo:
        try:
            e = evaluate_table(load_spectrum(spec), read_table(REFERENCE / f"{ref}.csv"))
            by_spec[spec].update(reference=ref, J_reference=e["J"])
        except Exception as exc:  # a reference that cannot be scored is reported, not fatal
            by_spec[spec].update(reference=ref, J_reference=f"error: {exc}")


def _fmt(r: dict, key: str, fmt: str) -> str:
    v = r.get(key, "")
    return format(v, fmt) if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)


def _print_row(r: dict) -> None:
    print(f"{r['spectrum'][-38:]:38s} {_fmt(r, 'nodes', '5d')} {_fmt(r, 'J_uniform', '9.4g')} "
          f"{_fmt(r, 'J_init', '9.4g')} {_fmt(r, 'J', '9.4g')} {_fmt(r, 'J_fine', '9.4g')} "
          f"{_fmt(r, 'ratio', '7.4f')} {_fmt(r, 'bias_rel', '8.1e')} "
          f"{'yes' if r['accepted'] else 'NO ':3s} {_fmt(r, 'seconds', '6.1f')} "
          f"{_fmt(r, 'cpu_seconds', '6.1f')}" + ("" if r["accepted"] else f"  {r['message'][-100:]}"),
          flush=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("spectra", nargs="*", help="spectra (default: the list above)")
    p.add_argument("--bar", type=float, default=0.05, help="J / J_uniform bar (default 0.05)")
    p.add_argument("--list", action="store_true", help="print the default list and stop")
    p.add_argument("--csv", default=None, help="also write the rows to this CSV file")
    p.add_argument("--tables", default=None, help="also copy each table to this folder")
    p.add_argument("extra", nargs="*", metavar="-- OPTION",
                   help="after '--': options passed to 'wavelength-pdf optimize'")
    argv = list(sys.argv[1:] if argv is None else argv)
    # Split at '--' before parsing: argparse would give what follows to the spectra.
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    args = p.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    specs = args.spectra or default_specs()
    if args.list:
        print("\n".join(specs))
        return 0

    print(f"{len(specs)} spectra, one 'wavelength-pdf optimize' process each, one XLA thread, "
          f"CPU affinity {sorted(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else '?'}")
    print(f"{'spectrum':38s} {'nodes':>5s} {'J unif':>9s} {'J init':>9s} {'J':>9s} {'J fine':>9s} "
          f"{'J/unif':>7s} {'bias':>8s} ok  {'wall s':>6s} {'cpu s':>6s}")
    rows: list[dict] = []
    tables = Path(args.tables) if args.tables else None
    with tempfile.TemporaryDirectory(prefix="bench-optimizer-") as tmp:
        for spec in specs:
            rows.append(run_one(spec, Path(tmp), extra, tables))
            _print_row(rows[-1])
        score_references(rows, Path(tmp))

    secs = [r["seconds"] for r in rows]
    cpus = [r["cpu_seconds"] for r in rows]
    ratios = [r.get("ratio", float("nan")) for r in rows]
    worst = max(rows, key=lambda r: r.get("ratio", float("inf")) if not math.isnan(r.get("ratio", float("nan"))) else float("inf"))
    slowest = max(rows, key=lambda r: r["cpu_seconds"])
    good = [r for r in rows if r["accepted"] and r.get("ratio", float("inf")) <= args.bar]
    print()
    print(f"whole-process seconds per spectrum: median {statistics.median(secs):.1f} wall, "
          f"{statistics.median(cpus):.1f} CPU; worst {max(secs):.1f} wall, {slowest['cpu_seconds']:.1f} CPU "
          f"({slowest['spectrum']}); total {sum(secs):.0f} wall, {sum(cpus):.0f} CPU")
    print(f"J / J_uniform: median {statistics.median([x for x in ratios if not math.isnan(x)] or [float('nan')]):.4f}, "
          f"worst {worst.get('ratio', float('nan')):.4f} ({worst['spectrum']})")
    print(f"accepted: {sum(r['accepted'] for r in rows)}/{len(rows)}; accepted and J <= {args.bar:g} x uniform: "
          f"{len(good)}/{len(rows)}")
    for r in rows:
        if r not in good:
            print(f"  above the bar or not accepted: {r['spectrum']} ratio {_fmt(r, 'ratio', '.4f')} "
                  f"accepted {r['accepted']}")
    refs = [r for r in rows if isinstance(r.get("J_reference"), float)]
    if refs:
        print("Dobos 2025 tables, J / ours: " + ", ".join(
            f"{r['reference']} {r['J_reference'] / r['J']:.2f}x" for r in refs if r.get("J")))
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
            w.writeheader()
            w.writerows(rows)
    return 0 if len(good) == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
