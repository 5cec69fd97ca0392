#!/usr/bin/env python3
"""What a wavelength table costs per path: ``pbrt --wavelength-pdf`` against visible sampling.

Renders one scene (default: the project's Cornell box, whose lamp the default table was
optimized for) alternately without a table (pbrt-v4's visible sampling, the default) and with
``--wavelength-pdf TABLE``, several times each, in one run, and reads the throughput ``pbrt``
reports in its closing line (paths per CPU-second of the render, scene loading excluded).
Alternating the runs spreads slow phases of a shared machine over both samplers. It prints
every run, the median throughput of each sampler and the median of the per-pair ratios
table / visible; the target is a cost of at most 2% per path (ratio >= 0.98).

``--tables A B`` compares two tables instead (A against B, the same way), and
``--nodes N`` compares the table with itself refined to N nodes: the same densities
exactly (the refined grid holds every original node, and the densities are interpolated
linearly, which they already are between nodes), so the paths are the same and only the
cost of looking a wavelength up in a larger table differs (the renderer's binary search).

The throughput counts whole paths. The path integrator's Russian roulette looks at the path
throughput, which depends on the wavelengths, so two samplers can give slightly different
path lengths on the same scene; ``--maxdepth 1`` (direct lighting only) makes the
comparison closer to the cost of the sampling itself.

Usage: scripts/bench_wavelength_pdf.py [--pbrt build/pbrt] [--scene S] [--table T]
           [--tables A B | --nodes N] [--reps 7] [--spp 16] [--resolution 128x128]
           [--nthreads 1] [--maxdepth N]
"""
from __future__ import annotations

import argparse
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
DEFAULT_SCENE = ROOT / "scenes" / "cornell-box" / "scene.pbrt"
DEFAULT_TABLE = ROOT / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
TARGET_RATIO = 0.98  # a table may cost at most 2% per path

CLOSING = re.compile(r"rendered in ([0-9.]+) s: (\d+) paths, ([0-9.]+) M paths/s, "
                     r"([0-9.]+) M paths per CPU-second")


def throughput(cmd: list[str]) -> float:
    """M paths per CPU-second of one render (raises with pbrt's message on failure)."""
    proc = subprocess.run(cmd, capture_output=True, text=True)
    m = CLOSING.search(proc.stderr)
    if proc.returncode != 0 or not m:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {proc.returncode}):\n{proc.stderr.strip()}")
    return float(m[4])


def refined_table(src: pathlib.Path, n_nodes: int, dest: pathlib.Path) -> int:
    """Write ``src``'s densities on a grid of ``n_nodes`` nodes that holds all of ``src``'s
    nodes (midpoints of the widest segments added); returns the node count written."""
    import numpy as np

    from wavelength_pdf import grids
    from wavelength_pdf.table import Table, read_table, write_table

    t = read_table(src)
    g = grids.fill_to(t.grid, n_nodes)
    pdfs = np.stack([np.interp(g, t.grid, p) for p in t.pdfs])
    write_table(dest, Table(grid=g, pdfs=pdfs, comments=[f"{src.name} on {g.size} nodes (same densities)"]))
    return int(g.size)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pbrt", type=pathlib.Path, default=ROOT / "build" / "pbrt")
    ap.add_argument("--scene", type=pathlib.Path, default=DEFAULT_SCENE)
    ap.add_argument("--table", type=pathlib.Path, default=DEFAULT_TABLE)
    ap.add_argument("--tables", type=pathlib.Path, nargs=2, metavar=("A", "B"), default=None,
                    help="compare table A against table B instead of a table against visible")
    ap.add_argument("--nodes", type=int, default=None,
                    help="compare --table against itself on this many nodes (same densities)")
    ap.add_argument("--reps", type=int, default=7, help="renders per sampler (alternating)")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--resolution", default="128x128")
    ap.add_argument("--nthreads", type=int, default=1)
    ap.add_argument("--maxdepth", type=int, default=None, help="default: the scene's")
    args = ap.parse_args()
    checks = [("pbrt", args.pbrt), ("scene", args.scene), ("table", args.table)]
    checks += [("table", t) for t in (args.tables or [])]
    for what, path in checks:
        if not path.is_file():
            print(f"bench_wavelength_pdf: {what} {path} not found", file=sys.stderr)
            return 1
    if args.reps < 1:
        print("bench_wavelength_pdf: --reps must be at least 1", file=sys.stderr)
        return 1

    if args.tables and args.nodes:
        print("bench_wavelength_pdf: give --tables or --nodes, not both", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        # The sampler that is measured ("table") and the one it is held against ("base").
        if args.tables:
            base_name, table_name = f"B {args.tables[1].name}", f"A {args.tables[0].name}"
            base, table = str(args.tables[1]), str(args.tables[0])
        elif args.nodes:
            dest = pathlib.Path(tmp) / "refined.csv"
            n = refined_table(args.table, args.nodes, dest)
            base_name, table_name = f"{args.table.name}", f"{n} nodes"
            base, table = str(args.table), str(dest)
        else:
            base_name, table_name, base, table = "visible", "table", None, str(args.table)
        samplers = {"base": ["--wavelength-sampling", "visible"] if base is None else ["--wavelength-pdf", base],
                    "table": ["--wavelength-pdf", table]}
        runs: dict[str, list[float]] = {name: [] for name in samplers}
        print(f"pbrt: {args.pbrt}\nscene: {args.scene}\n{table_name} ({table}) against {base_name}\n"
              f"{args.resolution}, {args.spp} spp, {args.nthreads} thread(s), maxdepth "
              f"{args.maxdepth if args.maxdepth is not None else 'of the scene'}, {args.reps} reps")
        for rep in range(args.reps):
            # Alternate which sampler goes first, so neither always runs on a warm machine.
            order = list(samplers) if rep % 2 == 0 else list(reversed(samplers))
            for name in order:
                cmd = [str(args.pbrt), "--spp", str(args.spp), "--seed", str(rep), "--resolution",
                       args.resolution, "--nthreads", str(args.nthreads),
                       "--outfile", str(pathlib.Path(tmp) / "out.exr"), *samplers[name]]
                if args.maxdepth is not None:
                    cmd += ["--maxdepth", str(args.maxdepth)]
                runs[name].append(throughput(cmd + [str(args.scene)]))
            print(f"  rep {rep + 1}: {base_name} {runs['base'][-1]:.4f}, {table_name} {runs['table'][-1]:.4f} "
                  f"M paths/CPU-s, ratio {runs['table'][-1] / runs['base'][-1]:.4f}")

    ratios = [t / v for t, v in zip(runs["table"], runs["base"])]
    ratio = statistics.median(ratios)
    print(f"median throughput: {base_name} {statistics.median(runs['base']):.4f}, "
          f"{table_name} {statistics.median(runs['table']):.4f} M paths per CPU-second")
    print(f"median ratio {table_name} / {base_name}: {ratio:.4f} (cost per path {100 * (1 / ratio - 1):+.2f}%; "
          f"target: ratio >= {TARGET_RATIO}, spread of the ratios {min(ratios):.4f}..{max(ratios):.4f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
