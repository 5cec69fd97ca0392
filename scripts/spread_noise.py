#!/usr/bin/env python3
"""How much of a measured pixel spread is noise: the median pixel's share of negative
eigenvalue mass, and that share pooled over the pixels (``transfer.negative_share``; 0 for a
covariance), for each number of wavelengths per path (``--wavelength-repeats``) of the
spread's renders, and for several path seeds averaged (design §6.8; docs/benchmark.md, "A
spread without negative variance").

    .venv/bin/python scripts/spread_noise.py --repeats 8 32 64 256 --seeds 1 4

prints a line per (repeats, seeds): the two shares and the wall time (renders and sums). The default scene is
the benchmark's ColorChecker at the lamp sweep's 32 x 24; the renders are kept in ``--workdir``.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=HERE.parent / "scenes" / "benchmark" / "colorchecker" / "scene.pbrt",
                    help="a pbrt-v4 scene lit by one kind of light (default: the benchmark's ColorChecker)")
    ap.add_argument("--size", default="32x24", help="the image size the spread is for, WxH (default 32x24)")
    ap.add_argument("--repeats", type=int, nargs="+", default=[8, 32, 64, 256],
                    help="wavelength repeats per path to compare (default 8 32 64 256)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 4],
                    help="numbers of path seeds averaged (seeds 1, 3, 5, ...; default 1 4)")
    ap.add_argument("--workdir", type=Path, default=HERE.parent / "out" / "spread-noise",
                    help="where the scene's copy and renders are kept (default out/spread-noise)")
    ap.add_argument("--pbrt", type=Path, default=None, help="the renderer (default: as design §7)")
    args = ap.parse_args(argv)
    try:
        w, h = (int(v) for v in args.size.lower().split("x"))
        if w < 1 or h < 1:
            raise ValueError
    except ValueError:
        ap.error(f"--size: {args.size!r} is not WxH with positive integers")
    if min(args.repeats) < 1 or min(args.seeds) < 1:
        ap.error("--repeats and --seeds must be at least 1")
    if not args.scene.is_file():
        ap.error(f"--scene: {args.scene} is not a file")

    from wavelength_pdf.evaluation import transfer

    print(f"{args.scene} at {w} x {h}, {transfer.SPREAD_FACTOR} x {transfer.SPREAD_FACTOR} sub-pixels; the "
          "negative share of the spread's absolute eigenvalue mass: the median pixel's, and pooled over the pixels")
    for repeats in args.repeats:
        for count in args.seeds:
            start = time.perf_counter()
            S = sum(transfer.spread(args.scene, args.workdir, (w, h), args.pbrt, repeats=repeats, seed=2 * k + 1)
                    for k in range(count)) / count
            print(f"repeats {repeats:4d}, seeds {count}: median {np.nanmedian(transfer.negative_share(S)):.3f}, "
                  f"pooled {transfer.negative_share(S, pooled=True):.3f} ({time.perf_counter() - start:.1f} s)",
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
