#!/usr/bin/env python3
"""How long emission sampling takes to build its table (design §1.7, --wavelength-sampling emission).

For each scene (the six evaluation scenes of ``../shared/scenes`` and the project's Cornell
boxes) and each weight, runs ``pbrt --emission-table`` ``--runs`` times and prints the median
and the largest of the times ``pbrt`` reports for the whole build: the scene's emitted power
(every light), the weight and the equal-mass cuts (the scene's parsing is not included). With
``--upstream PATH`` (a pbrt-v4 patched by integrations/pbrt-v4), also the time the patched binary
reports, rendering one pixel with ``--wavelength-sampling emission``.

Usage::

    .venv/bin/python scripts/bench_emission_table.py [--pbrt build/pbrt] [--runs 5] [--upstream PATH]
"""
from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
WEIGHTS = ("spd", "luminance", "xyz")
TIME = re.compile(r"built in ([0-9.eE+-]+) ms")


def scenes(shared: Path) -> list[Path]:
    out = sorted(shared.glob("scenes/*/scene-v4.pbrt"))
    return out + [ROOT / "scenes" / "cornell-box" / "scene.pbrt", ROOT / "scenes" / "cornell-box-two-lamps" / "scene.pbrt"]


def built_ms(cmd: list[str]) -> float:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    m = TIME.search(proc.stderr + proc.stdout)
    if proc.returncode != 0 or not m:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-1500:]}")
    return float(m[1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pbrt", type=Path, default=ROOT / "build" / "pbrt")
    ap.add_argument("--shared", type=Path, default=ROOT.parent / "shared")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--upstream", type=Path, default=None, help="a patched upstream pbrt-v4 binary")
    args = ap.parse_args()
    rows = ["| scene | " + " | ".join(f"{w} median (max), ms" for w in WEIGHTS)
            + (" | patched upstream, spd, ms |" if args.upstream else " |"),
            "|---|" + "---|" * len(WEIGHTS) + ("---|" if args.upstream else "")]
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "table.csv"
        for scene in scenes(args.shared):
            cells = []
            for w in WEIGHTS:
                t = [built_ms([str(args.pbrt), "--emission-table", str(out), "--emission-weight", w, str(scene)])
                     for _ in range(args.runs)]
                worst = max(worst, max(t))
                cells.append(f"{statistics.median(t):.3g} ({max(t):.3g})")
            if args.upstream:
                t = [built_ms([str(args.upstream), "--wavelength-sampling", "emission", "--spp", "1",
                               "--pixelbounds", "0,1,0,1", "--outfile", str(Path(tmp) / "x.exr"), str(scene)])
                     for _ in range(args.runs)]
                cells.append(f"{statistics.median(t):.3g} ({max(t):.3g})")
            name = scene.parent.name if scene.name == "scene-v4.pbrt" else f"{scene.parent.name} (project)"
            rows.append(f"| {name} | " + " | ".join(cells) + " |")
            print(rows[-1], file=sys.stderr, flush=True)
    print("\n".join(rows))
    print(f"\nlargest of all: {worst:.3g} ms ({args.runs} runs per cell; this repository's pbrt)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
