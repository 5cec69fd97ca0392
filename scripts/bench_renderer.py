#!/usr/bin/env python3
"""Renderer benchmark: paths per CPU-second for each evaluation scene, in one run.

Renders the six evaluation scenes ``../shared/scenes/<scene>/scene-v4.pbrt`` (cornell-box,
veach-mis, teapot, veach-bidir, staircase, glass-of-water) at 256x256 with maximum depth 5
and prints the throughput that ``pbrt`` reports in its closing line (paths / (user + system
CPU time of the render)). A scene that is missing or fails to render is listed with the
reason, and the exit status is then 1. For scale, upstream pbrt-v4 renders the
256x256 Cornell box (maxdepth 5) at about 0.17 M paths per CPU-second on a 2-core machine
of this kind; the ratio to that figure is printed too.

Usage: scripts/bench_renderer.py [--pbrt build/pbrt] [--spp 16] [--shared ../shared]
"""
from __future__ import annotations

import argparse
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
UPSTREAM_CORNELL_MPATHS_PER_CPU_S = 0.17  # pbrt-v4, 256x256 Cornell box, maxdepth 5, 2 cores
# The evaluation scenes (../shared/scenes/README.md), the Cornell box first.
SCENES = ("cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase", "glass-of-water")

CLOSING = re.compile(r"rendered in ([0-9.]+) s: (\d+) paths, ([0-9.]+) M paths/s, ([0-9.]+) M paths per CPU-second")


def bench_scene(pbrt: pathlib.Path, scene: pathlib.Path, spp: int, out: pathlib.Path) -> tuple[str, str]:
    """Renders one scene; returns (status, text) where status is "ok" or "skipped"."""
    cmd = [str(pbrt), "--resolution", "256x256", "--maxdepth", "5", "--spp", str(spp),
           "--seed", "1", "--outfile", str(out), str(scene)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        lines = [line for line in proc.stderr.splitlines() if line.startswith("pbrt:")]
        return "skipped", (lines[-1] if lines else proc.stderr.strip()[-200:])
    m = CLOSING.search(proc.stderr)
    if not m:
        return "skipped", "no closing line in the output"
    wall, paths, per_s, per_cpu_s = float(m[1]), int(m[2]), float(m[3]), float(m[4])
    return "ok", f"{per_cpu_s:7.3f} M paths/CPU-s  ({per_s:.3f} M paths/s wall, {paths} paths in {wall:.2f} s)"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pbrt", type=pathlib.Path, default=ROOT / "build" / "pbrt")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--shared", type=pathlib.Path, default=ROOT.parent / "shared")
    args = ap.parse_args()
    if not args.pbrt.exists():
        print(f"bench_renderer: {args.pbrt} not found (build it with scripts/setup.sh)", file=sys.stderr)
        return 1
    if not (args.shared / "scenes").is_dir():
        print(f"bench_renderer: no scenes under {args.shared / 'scenes'}", file=sys.stderr)
        return 1
    scenes = [args.shared / "scenes" / name / "scene-v4.pbrt" for name in SCENES]
    failures = 0
    print(f"pbrt: {args.pbrt}; 256x256, maxdepth 5, {args.spp} spp")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            name = scene.parent.name
            if not scene.exists():
                print(f"  {name:15s} missing: {scene}")
                failures += 1
                continue
            status, text = bench_scene(args.pbrt, scene, args.spp, pathlib.Path(tmp) / "out.exr")
            failures += status != "ok"
            print(f"  {name:15s} {text}" if status == "ok" else f"  {name:15s} skipped: {text}")
            if status == "ok" and name == "cornell-box":
                per_cpu = float(text.split()[0])
                print(f"  {'':15s} {per_cpu / UPSTREAM_CORNELL_MPATHS_PER_CPU_S:.2f}x upstream pbrt-v4's "
                      f"{UPSTREAM_CORNELL_MPATHS_PER_CPU_S} M paths/CPU-s")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
