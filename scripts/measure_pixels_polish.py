"""The ``pixels`` objective in the image (design §4.6): a lamp's J table polished for one scene's
pixels at one spp (``optimize.optimize_for_pixels``), against the J table it started from and
the lamp's own stratified table (design §1.7, the strongest simple sampler under spiky lamps).

For each scene: the lamp's J table (``optimize_spectrum``), the scene's transfer
(``evaluation.transfer.of_file``, at ``--resolution-scale`` of its size), the polish, each
table's predicted wavelength error at ``--spp`` and at a quarter and four times it
(``evaluation.choose.wavelength_error``) and at ``--spp`` with every pixel's incoherence 0
(``predicted_coherent``: one spectrum per pixel, as a render with ``--disable-pixel-jitter``
gives where the pixels see surfaces larger than a pixel), then PAIRS seed pairs of each
table's render of the scene lit by the lamp, alternating table by table, and the benchmark's
``de2`` of each pair (the mean over the lit pixels of CIEDE2000(A, B)^2 / 2: no reference
needed), with the CPU seconds each image records. With ``--floor`` also the benchmark's
floor, and each table's ``de2`` above it over J's (``above_floor_vs_J``): the part of the
error the prediction speaks of, where path noise would otherwise pull every ratio towards 1.
``--choose`` adds the table ``wavelength-pdf choose --polish`` picks (row ``image``).
``--simple`` adds the benchmark's other simple samplers, and with ``--floor`` each table's
error above the floor over the best simple sampler's (``above_floor_vs_best_simple``). With
``--spread`` the transfer carries each pixel's spread (``transfer.spread``: the spectra a
pixel's samples see, two or more at a patch's edge), which the predictions and the polish
then use in place of the incoherence; give the transfer the images' size (``--transfer-size``).

    .venv/bin/python scripts/measure_pixels_polish.py --spectrum cie:FL11 --spp 64 --pairs 3 \\
        --scenes scenes/benchmark/colorchecker/scene.pbrt [--floor] [--render-args=--wavelength-net] \\
        [--spread --transfer-size 320x240 --transfer-dir out/transfer-keep] [--out results.csv]
"""
from __future__ import annotations

import argparse
import csv
import dataclasses
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "python"))

from wavelength_pdf import predict as P  # noqa: E402
from wavelength_pdf.cli.evaluate import _resolution  # noqa: E402  (evaluate's --resolution WxH)
from wavelength_pdf.evaluation import transfer  # noqa: E402
from wavelength_pdf.evaluation.benchmark.grid import Job  # noqa: E402
from wavelength_pdf.evaluation.benchmark.measures import _delta_e, lit_pixels  # noqa: E402
from wavelength_pdf.evaluation.choose import for_image, simple_tables, wavelength_error  # noqa: E402
from wavelength_pdf.evaluation.metrics import rgb_to_lab  # noqa: E402
from wavelength_pdf.evaluation.scene_edit import edit_scene  # noqa: E402
from wavelength_pdf.exr import read_header, read_rgb  # noqa: E402
from wavelength_pdf.optimize import optimize_for_pixels, optimize_spectrum  # noqa: E402
from wavelength_pdf.spectra import load_spectrum  # noqa: E402
from wavelength_pdf.stratified import stratified_table  # noqa: E402
from wavelength_pdf.table import write_table  # noqa: E402

FLOOR_REPEATS = Job.floor_repeats  # the benchmark's


def measure(scene: Path, spectrum, a: argparse.Namespace, work: Path) -> list[dict]:
    work.mkdir(parents=True, exist_ok=True)
    J = optimize_spectrum(spectrum).table
    lamp = stratified_table(spectrum, "spd")
    folder = (a.transfer_dir / f"{scene.parent.name}-{scene.stem}") if a.transfer_dir else work / "transfer"
    tr = transfer.of_file(scene, folder, a.transfer_size or a.resolution_scale, a.pbrt, transfer.SPP,
                          with_spread=a.spread)
    # The scene with every pixel's incoherence 0: each pixel's samples one path whose u is
    # stratified over them, what a render without pixel jitter (one spectrum per pixel) shows.
    coherent_tr = dataclasses.replace(tr, incoherence=np.zeros_like(tr.incoherence), spread=None)
    start = time.monotonic()
    aim = coherent_tr if a.coherent else tr
    polished = optimize_for_pixels(spectrum, {"J": J, "lamp": lamp}[a.polish_from], aim.t, aim.centres, a.spp,
                                   incoherence=aim.incoherence, terminated=aim.terminated, spread=aim.spread)
    polish_s = time.monotonic() - start
    tables = {"lamp": lamp, "J": J, "pixels": polished.table}
    chosen = ""
    if a.choose:  # the product's choice: wavelength-pdf choose SCENE J.csv --polish [--spread]
        best = for_image(spectrum, tr, a.spp, {"J": J})[0]
        tables["image"], chosen = best.table, best.name
    if a.simple:  # the benchmark's other simple samplers (the lamp's table is its spd)
        tables.update({k: v for k, v in simple_tables(spectrum).items() if k != "spd"})
    basis = P.hat_basis(tr.centres, transfer.LO, transfer.HI)
    spps = (a.spp // 4, a.spp, 4 * a.spp)
    predicted = {name: {spp: wavelength_error(t, spectrum, basis, tr, spp) for spp in spps}
                 for name, t in tables.items()}
    coherent = {name: wavelength_error(t, spectrum, basis, coherent_tr, a.spp) for name, t in tables.items()}
    for name, t in tables.items():
        write_table(work / f"{name}.csv", t)
    lit = edit_scene(scene, spectrum, work / "lit.pbrt")
    # The benchmark's floor (design §6): the lamp's table with eight wavelength sets per path,
    # the error left when wavelength noise is all but gone; each table's de2 above it is the
    # part the prediction speaks of.
    runs = {name: (name, []) for name in tables}
    if a.floor:
        runs["floor"] = ("lamp", ["--wavelength-repeats", str(FLOOR_REPEATS)])
    images = {name: [] for name in runs}
    cpu = {name: [] for name in runs}
    # One render at a time, the tables alternating seed by seed (a drift of the machine's
    # speed falls on every table alike).
    for seed in range(1, 2 * a.pairs + 1):
        print(f"{scene.parent.name}: seed {seed} of {2 * a.pairs}", file=sys.stderr)
        for name, (table, extra) in runs.items():
            out = work / f"{name}-{seed}.exr"
            r = subprocess.run([str(a.pbrt), "--quiet", "--nthreads", str(a.threads), "--spp", str(a.spp),
                                "--seed", str(seed), "--wavelength-pdf", str(work / f"{table}.csv"), *extra,
                                *a.render_args.split(), "--outfile", str(out), str(lit)],
                               capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit(r.stderr)
            images[name].append(read_rgb(out))
            cpu[name].append(float(read_header(out)["renderCPUSeconds"]))
    mask = lit_pixels(np.mean([im for ims in images.values() for im in ims], axis=0))
    de2 = {name: [float(np.mean(_delta_e(rgb_to_lab(ims[2 * i]), rgb_to_lab(ims[2 * i + 1]))[mask] ** 2) / 2)
                  for i in range(a.pairs)] for name, ims in images.items()}
    floor = float(np.mean(de2["floor"])) if a.floor else None
    shown = scene.relative_to(REPO) if scene.is_relative_to(REPO) else scene
    polish = f"from {a.polish_from}" + (", coherent" if a.coherent else "") + (", spread" if a.spread else "")
    simple = [n for n in tables if n not in ("J", "pixels", "image")]
    best_simple = min(float(np.mean(de2[n])) for n in simple) - floor if floor is not None and a.simple else None
    rows = []
    for name in runs:
        e = float(np.mean(de2[name]))
        is_table = name in tables
        above = ""
        if floor is not None and is_table:
            above = f"{(e - floor) / (np.mean(de2['J']) - floor):.3f}"
        rows.append({"scene": str(shown), "spectrum": a.spectrum, "spp": a.spp, "pairs": a.pairs,
                     "render_args": a.render_args, "polish": polish, "table": name,
                     "de2": f"{e:.5g}", "de2_se": f"{np.std(de2[name], ddof=1) / np.sqrt(a.pairs):.2g}",
                     "de2_vs_J": f"{e / np.mean(de2['J']):.3f}", "above_floor_vs_J": above,
                     "above_floor_vs_best_simple": f"{(e - floor) / best_simple:.3f}"
                     if best_simple is not None and is_table else "",
                     "cpu_s": f"{np.mean(cpu[name]):.3f}",
                     **{f"predicted_{spp}spp": f"{predicted[name][spp]:.4g}" if is_table else "" for spp in spps},
                     "predicted_vs_J": f"{predicted[name][a.spp] / predicted['J'][a.spp]:.3f}" if is_table else "",
                     f"predicted_coherent_{a.spp}spp": f"{coherent[name]:.4g}" if is_table else "",
                     "polish_s": f"{polish_s:.1f}" if name == "pixels" else "",
                     "chosen": chosen if name == "image" else ""})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spectrum", default="cie:FL11", help="the lamp (a spectrum spec, as `wavelength-pdf optimize`)")
    ap.add_argument("--scenes", nargs="+", type=Path, default=[REPO / "scenes/benchmark/colorchecker/scene.pbrt"],
                    help="pbrt-v4 scenes, each relit by the lamp")
    ap.add_argument("--spp", type=int, default=64, help="the spp the polish aims at and the renders use")
    ap.add_argument("--pairs", type=int, default=3, help="seed pairs per table")
    ap.add_argument("--threads", type=int, default=2, help="render threads")
    ap.add_argument("--resolution-scale", type=float, default=0.25,
                    help="the transfer copy's size, a share of 1280 x 720 (the benchmark's copies)")
    ap.add_argument("--transfer-size", type=_resolution, default=None, metavar="WxH",
                    help="the transfer copy's size in pixels instead (the images', e.g. 320x240 for the "
                         "ColorChecker, for --spread)")
    ap.add_argument("--transfer-dir", type=Path, default=None,
                    help="keep the transfer's renders here, one folder per scene, for the next run (default: "
                         "a temporary folder)")
    ap.add_argument("--spread", action="store_true",
                    help="predict and polish with each pixel's spread (transfer.spread: the spectra its samples "
                         "see) in place of its incoherence; the transfer should then be at the images' size")
    ap.add_argument("--pbrt", type=Path, default=REPO / "build" / "pbrt", help="the renderer")
    ap.add_argument("--render-args", default="", help="extra flags for every measured render, not the transfer's "
                    "(e.g. --render-args=--wavelength-net)")
    ap.add_argument("--floor", action="store_true", help="also render the benchmark's floor (the lamp's table with "
                    f"{FLOOR_REPEATS} wavelength sets per path, {FLOOR_REPEATS} times a render's cost) and give each "
                    "table's de2 above it over J's")
    ap.add_argument("--polish-from", choices=("J", "lamp"), default="J",
                    help="the table the polish starts from: the lamp's J table or its stratified table")
    ap.add_argument("--coherent", action="store_true",
                    help="polish for every pixel's incoherence 0 (one spectrum per pixel, as without pixel jitter)")
    ap.add_argument("--simple", action="store_true",
                    help="also render the benchmark's other simple samplers (uniform, visible, luminance, xyz; the "
                         "lamp's table is its spd) and, with --floor, give each table's de2 above the floor over "
                         "the best simple sampler's")
    ap.add_argument("--choose", action="store_true",
                    help="also the table `wavelength-pdf choose SCENE J.csv --polish` picks (row `image`: the best "
                         "by the prediction of the simple samplers, J's table and both polished; with --spread, "
                         "as choose --spread)")
    ap.add_argument("--out", type=Path, help="write the rows as CSV here")
    a = ap.parse_args()
    if a.spp < 4 or a.pairs < 2:
        ap.error("--spp must be at least 4 and --pairs at least 2")
    for s in a.scenes:
        if not s.is_file():
            ap.error(f"{s}: no such scene")
    if not a.pbrt.is_file():
        ap.error(f"{a.pbrt}: no renderer (bash scripts/setup.sh builds it)")
    spectrum = load_spectrum(a.spectrum)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, scene in enumerate(a.scenes):
            rows += measure(scene.resolve(), spectrum, a, Path(tmp) / str(i))
    w = csv.DictWriter(sys.stdout, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    if a.out:
        tmp_out = a.out.with_suffix(a.out.suffix + ".tmp")
        with open(tmp_out, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        tmp_out.replace(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
