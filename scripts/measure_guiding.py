"""Wavelength guiding against whole-scene emission sampling and visible sampling (docs/guiding.md).

For each scene, at a reduced size: PAIRS seed pairs of each sampler at one spp; the error of a
sampler is the benchmark's ``de2`` (wavelength_pdf.evaluation.benchmark.measures: the mean over
the lit pixels of CIEDE2000(A, B)^2 / 2 of a seed pair, no reference needed), averaged over the
pairs with its standard error. Equal CPU time comes from the CPU seconds every image records
(``renderCPUSeconds``, which for guiding includes the pre-pass and the tables) through the
benchmark's ``equal_time_ratio`` (a squared error falls as 1/spp).

    .venv/bin/python scripts/measure_guiding.py [--spp 64] [--pairs 3]
        [--size 80 60] [--threads 1] [--out docs/guiding/measurement.csv]
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "python"))

from wavelength_pdf.evaluation.benchmark.measures import _delta_e, equal_time_ratio, lit_pixels  # noqa: E402
from wavelength_pdf.evaluation.metrics import rgb_to_lab  # noqa: E402
from wavelength_pdf.evaluation.scene_edit import edit_scene  # noqa: E402
from wavelength_pdf.exr import read_header, read_rgb  # noqa: E402

SCENES = ("night-street", "window-room")
SAMPLERS = {
    "visible": ("--wavelength-sampling", "visible"),
    "emission": ("--wavelength-sampling", "emission"),
    "guided": ("--wavelength-guiding",),
}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--size", type=int, nargs=2, default=(80, 60))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--pbrt", type=Path, default=REPO / "build" / "pbrt")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--guiding-args", default="", help="extra flags for the guided renders")
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in SCENES:
            scene = edit_scene(REPO / "scenes" / "benchmark" / name / "scene.pbrt", None, tmp / f"{name}.pbrt",
                               resolution=tuple(a.size))
            images, cpu = {}, {}
            for sampler, args in SAMPLERS.items():
                if sampler == "guided":
                    args = args + tuple(a.guiding_args.split())
                images[sampler], cpu[sampler] = [], []
                for seed in range(1, 2 * a.pairs + 1):
                    out = tmp / f"{name}-{sampler}-{seed}.exr"
                    r = subprocess.run([str(a.pbrt), "--quiet", "--nthreads", str(a.threads), "--spp", str(a.spp),
                                        "--seed", str(seed), "--outfile", str(out), *args, str(scene)],
                                       capture_output=True, text=True)
                    if r.returncode != 0:
                        sys.exit(r.stderr)
                    images[sampler].append(read_rgb(out))
                    cpu[sampler].append(float(read_header(out)["renderCPUSeconds"]))
                    if sampler == "guided" and seed == 1:
                        h = read_header(out)
                        print(f"{name}: guided with {h['wavelengthGuidingTables']} tables, "
                              f"{h['wavelengthGuidingKinds']} kinds, pre-pass "
                              f"{h['wavelengthGuidingCPUSeconds']:.3f} s CPU", file=sys.stderr)
            # The lit pixels of the mean of every image (lamps seen directly left out, as the
            # benchmark does).
            mask = lit_pixels(np.mean([im for ims in images.values() for im in ims], axis=0))
            result = {}
            for sampler, ims in images.items():
                de2 = [float(np.mean(_delta_e(rgb_to_lab(ims[2 * i]), rgb_to_lab(ims[2 * i + 1]))[mask] ** 2) / 2)
                       for i in range(a.pairs)]
                result[sampler] = (np.mean(de2), np.std(de2, ddof=1) / np.sqrt(a.pairs) if a.pairs > 1 else np.nan,
                                   float(np.mean(cpu[sampler])))
            for sampler, (de2, se, t) in result.items():
                e_em, _, t_em = result["emission"]
                e_vis, _, t_vis = result["visible"]
                rows.append({"scene": name, "sampler": sampler, "spp": a.spp, "size": f"{a.size[0]}x{a.size[1]}",
                             "pairs": a.pairs, "de2": f"{de2:.5g}", "de2_se": f"{se:.2g}", "cpu_s": f"{t:.3f}",
                             "de2_vs_emission_equal_spp": f"{de2 / e_em:.3f}",
                             "de2_vs_emission_equal_time": f"{equal_time_ratio(de2, t, e_em, t_em):.3f}",
                             "de2_vs_visible_equal_time": f"{equal_time_ratio(de2, t, e_vis, t_vis):.3f}"})
    w = csv.DictWriter(sys.stdout, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        with open(a.out, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
