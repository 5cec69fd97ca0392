"""Wavelength guiding against whole-scene emission sampling and visible sampling (docs/guiding.md).

For each scene, at a reduced size: PAIRS seed pairs of each sampler at one spp; the error of a
sampler is the benchmark's ``de2`` (wavelength_pdf.evaluation.benchmark.measures: the mean over
the lit pixels of CIEDE2000(A, B)^2 / 2 of a seed pair, no reference needed), averaged over the
pairs with its standard error. Equal CPU time comes from the CPU seconds every image records
(``renderCPUSeconds``, which for guiding includes the pre-pass and the tables) through the
benchmark's ``equal_time_ratio`` (a squared error falls as 1/spp).

The samplers: pbrt-v4's visible sampling, whole-scene emission sampling (one table), guided
with emission tables per mixture, guided with optimized tables per mixture (end to end: the
pre-pass writes the mixtures' spectra, ``wavelength-pdf batch`` optimizes them, the render reads
them; the optimizer's seconds are reported apart, since its tables are cached by content and
serve every later render of the scene), guided with the tables ``wavelength-pdf choose-guiding``
keeps per mixture among its emission table and the optimized routes of ``--choose-from`` (the
prediction's renders reported apart too, as ``choose_s``), guided with the tables
``choose-guiding --polish`` keeps among those and each of them and the emission table polished
for its table's pixels (``guided-polished``), and the floor (emission sampling with
``--wavelength-repeats 8``: what is left when wavelength noise is all but gone, design §6.7).
The renders run one at a time, the samplers alternating seed by seed; the CSV gives each
sampler's CPU seconds (mean, least, most). ``--per-table`` breaks each sampler's error down by
the guiding table of the pixels. Beside ``de2`` the CSV gives ``mean_de``, the mean ΔE00 of the
pairs over sqrt(2), and its ratios at equal time (it falls as spp^-1/2).

    .venv/bin/python scripts/measure_guiding.py [--spp 64] [--pairs 3] [--size 80 60]
        [--threads 1] [--samplers ...] [--choose-from white scene] [--render-args=--wavelength-net]
        [--out docs/guiding/measurement.csv]
        [--per-table docs/guiding/per-table.csv] [--pictures docs/guiding]
"""
from __future__ import annotations

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time
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
    "guided-optimized": ("--wavelength-guiding",),  # + --wavelength-guiding-tables, below
    "guided-chosen": ("--wavelength-guiding",),     # the same, the tables choose-guiding kept
    "guided-polished": ("--wavelength-guiding",),   # the same, choose-guiding --polish's
    "floor": ("--wavelength-sampling", "emission", "--wavelength-repeats", "8"),
}


def mixture_spectra(pbrt: Path, scene: Path, common: list[str], guiding: tuple[str, ...], work: Path) -> Path:
    """The pre-pass's mixture spectra, tile map and emission tables at the render's settings."""
    spectra = work / "spectra"
    spectra.mkdir(parents=True, exist_ok=True)
    r = subprocess.run([str(pbrt), *common, "--wavelength-guiding", *guiding,
                        "--wavelength-guiding-spectra", str(spectra), str(scene)], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(r.stderr)
    return spectra


def optimized_tables(pbrt: Path, scene: Path, spectra: Path, work: Path, threads: int, batch_args: list[str],
                     colours: str = "white") -> tuple[Path, float]:
    """The mixture spectra optimized by ``wavelength-pdf batch`` for ``colours`` (design §4.5;
    ``scene``: the scene's own materials, ``pbrt --material-reflectances``): (folder, seconds,
    the renderer's material listing included)."""
    tables = work / f"tables-{Path(colours).stem}"
    start = time.perf_counter()
    if colours == "scene":
        materials = work / "materials.csv"
        r = subprocess.run([str(pbrt), "--material-reflectances", str(materials), str(scene)],
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(r.stderr)
        colours = str(materials)
    batch_args = [*batch_args, "--reflectances", colours]
    r = subprocess.run([sys.executable, "-m", "wavelength_pdf", "batch", str(spectra), "-o", str(tables),
                        "--jobs", str(threads), "--quiet", *batch_args], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(REPO / "python")})
    if r.returncode not in (0, 1):  # 1: a table not accepted (the render falls back to emission's)
        sys.exit(r.stderr)
    return tables, time.perf_counter() - start


def chosen_tables(pbrt: Path, scene: Path, spectra: Path, routes: dict[str, Path], spp: int,
                  work: Path, polish: bool = False) -> tuple[Path | None, float, str]:
    """``wavelength-pdf choose-guiding`` over the optimized routes (with ``polish``, also each
    route and the emission tables polished for their pixels): (the folder, None when every
    mixture keeps its emission table; seconds; each table's choice)."""
    from wavelength_pdf.evaluation.guiding_choice import EMISSION, choose_guiding_tables

    start = time.perf_counter()
    folder = work / ("polished" if polish else "chosen")
    choices = choose_guiding_tables(scene, spectra, routes, spp, folder, work / "transfer", pbrt=pbrt, polish=polish)
    picks = " ".join(f"{c.table}:{c.chosen}" for c in choices)
    kept = any(c.chosen != EMISSION for c in choices)
    return (folder if kept else None), time.perf_counter() - start, picks


def pictures(where: Path, name: str, mean: np.ndarray, maps: dict, index: np.ndarray, mask: np.ndarray) -> None:
    """The mean image, its table map and each sampler's error map of its first seed pair
    (``maps``: sampler -> per pair, the ΔE00 map)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = [s for s in ("visible", "emission", "guided", "guided-optimized", "guided-chosen", "guided-polished",
                         "floor") if s in maps]
    first = {s: maps[s][0] for s in shown}
    top = float(np.percentile(np.concatenate([m[mask] for m in first.values()]), 99))
    fig, axes = plt.subplots(1, 2 + len(shown), figsize=(3.2 * (2 + len(shown)), 3.0), constrained_layout=True)
    srgb = np.clip(mean / max(float(np.percentile(mean, 99)), 1e-12), 0, 1) ** (1 / 2.2)
    axes[0].imshow(srgb)
    axes[0].set_title(f"{name} (mean of all renders)", fontsize=8)
    axes[1].imshow(index, cmap="tab20", interpolation="nearest", vmin=0, vmax=19)
    axes[1].set_title(f"table map: {int(index.max()) + 1} tables", fontsize=8)
    for ax, s in zip(axes[2:], shown):
        im = ax.imshow(np.where(mask, first[s], np.nan), cmap="magma", vmin=0, vmax=top)
        ax.set_title(f"{s}: ΔE00 of a seed pair, mean {np.mean(first[s][mask]):.2f}", fontsize=8)
    fig.colorbar(im, ax=axes[2:].tolist(), shrink=0.8, label="CIEDE2000")
    for ax in axes:
        ax.set_axis_off()
    where.mkdir(parents=True, exist_ok=True)
    fig.savefig(where / f"{name}.png", dpi=110)
    plt.close(fig)


def table_shares(clusters: Path) -> dict[int, str]:
    """Each guiding table's kind shares from the renderer's clusters.csv, as text
    ('scene.pbrt:LINE 0.92; ...', a kind by its strongest light's line)."""
    from wavelength_pdf.evaluation.guiding_choice import cluster_rows

    return {int(r["table"]): "; ".join(f"{Path(k.removeprefix('share ')).name.rsplit(':', 1)[0]} {float(v):.2f}"
                                       for k, v in r.items() if k.startswith("share "))
            for r in cluster_rows(clusters)}


def per_table(name: str, a: argparse.Namespace, maps: dict, index: np.ndarray, mask: np.ndarray,
              shares: dict[int, str]) -> list[dict]:
    """Each sampler's ``de2`` over the lit pixels of each guiding table (every guided render of
    the scene uses the same tables' tiles: the pre-pass has its own seed), and its ratio to
    guiding with emission tables there: where optimizing the mixtures pays and where it does not."""
    rows = []
    for k in range(int(index.max()) + 1):
        pixels = mask & (index == k)
        if not pixels.any():
            continue
        de2 = {s: float(np.mean([np.mean(m[pixels] ** 2) / 2 for m in pairs])) for s, pairs in maps.items()}
        for s, e in de2.items():
            rows.append({"scene": name, "table": k, "shares": shares.get(k, ""), "lit_pixels": int(pixels.sum()),
                         "sampler": s, "spp": a.spp,
                         "de2": f"{e:.5g}", "de2_vs_guided_equal_spp": f"{e / de2['guided']:.3f}"})
    return rows


def table_index(path: Path) -> np.ndarray:
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        return np.asarray(f.channels()["wavelengthTable.index"].pixels)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--size", type=int, nargs=2, default=(80, 60))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--pbrt", type=Path, default=REPO / "build" / "pbrt")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--guiding-args", default="", help="extra flags for the guided renders")
    ap.add_argument("--render-args", default="", help="extra flags for every render and the pre-pass runs "
                    "(e.g. --render-args=--wavelength-net)")
    ap.add_argument("--batch-args", default="", help="extra flags for wavelength-pdf batch (e.g. "
                    "'--range 360 830 --grid-step 5'; default: its own range, 380-780 nm)")
    ap.add_argument("--colours", default="white", help="the surface colours the mixture tables are optimized "
                    "for (wavelength-pdf batch --reflectances): white (default), colorchecker, scene (the "
                    "scene's own materials) or a reflectance CSV")
    ap.add_argument("--choose-from", nargs="+", default=["white", "scene"], metavar="COLOURS",
                    help="guided-chosen and guided-polished: the optimized routes (as --colours) that "
                         "wavelength-pdf choose-guiding chooses from, table by table, beside the emission tables "
                         "(default: white scene)")
    ap.add_argument("--pictures", type=Path, help="write SCENE.png (image, table map, error maps) here")
    ap.add_argument("--keep", type=Path, metavar="DIR",
                    help="keep every render (SCENE-SAMPLER-SEED.exr) and the tables it used here, to inspect")
    ap.add_argument("--per-table", type=Path, metavar="CSV",
                    help="write each sampler's de2 over each guiding table's pixels here")
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), help="benchmark scenes (default: %(default)s)")
    ap.add_argument("--samplers", nargs="+", default=list(SAMPLERS), choices=list(SAMPLERS),
                    help="the samplers to render (default: all; emission and guided are always "
                         "rendered, the ratios are taken against them)")
    a = ap.parse_args()
    samplers = {s: args for s, args in SAMPLERS.items() if s in {*a.samplers, "emission", "guided"}}
    rows, per_table_rows = [], []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in a.scenes:
            scene = edit_scene(REPO / "scenes" / "benchmark" / name / "scene.pbrt", None, tmp / f"{name}.pbrt",
                               resolution=tuple(a.size))
            common = ["--quiet", "--nthreads", str(a.threads), "--spp", str(a.spp), *a.render_args.split()]
            guiding = tuple(a.guiding_args.split())
            tables, optimizer_s = None, float("nan")
            # guided-chosen and guided-polished: (tables folder, choose-guiding's seconds, its choices)
            chosen: dict[str, tuple[Path | None, float, str]] = {}
            choosing = [s for s in ("guided-chosen", "guided-polished") if s in samplers]
            if {"guided-optimized", *choosing} & set(samplers):
                spectra = mixture_spectra(a.pbrt, scene, common, guiding, tmp / name)
                needed = ([a.colours] if "guided-optimized" in samplers else []) + (a.choose_from if choosing else [])
                routes = {c: optimized_tables(a.pbrt, scene, spectra, tmp / name, a.threads, a.batch_args.split(), c)
                          for c in dict.fromkeys(needed)}
                for c, (folder, secs) in routes.items():
                    print(f"{name}: optimized {len(list(folder.glob('mixture-*.csv')))} mixture tables for {c} in "
                          f"{secs:.1f} s", file=sys.stderr)
                if "guided-optimized" in samplers:
                    tables, optimizer_s = routes[a.colours]
                for s in choosing:
                    chosen[s] = chosen_tables(a.pbrt, scene, spectra, {c: routes[c][0] for c in a.choose_from},
                                              a.spp, tmp / name, polish=s == "guided-polished")
                    print(f"{name}: choose-guiding{' --polish' if s == 'guided-polished' else ''} in "
                          f"{chosen[s][1]:.1f} s: {chosen[s][2]}", file=sys.stderr)
            images = {sampler: [] for sampler in samplers}
            cpu = {sampler: [] for sampler in samplers}
            prepass, guide_bytes = {}, {}
            # One render at a time, the samplers alternating seed by seed, so that a change in
            # the machine's speed during the run falls on every sampler alike.
            for seed in range(1, 2 * a.pairs + 1):
                print(f"{name}: seed {seed} of {2 * a.pairs}", file=sys.stderr)
                for sampler, args in samplers.items():
                    if sampler.startswith("guided"):
                        args = args + guiding
                    if sampler == "guided-optimized":
                        args = args + ("--wavelength-guiding-tables", str(tables))
                    if sampler in chosen and chosen[sampler][0] is not None:
                        args = args + ("--wavelength-guiding-tables", str(chosen[sampler][0]))
                    out = tmp / f"{name}-{sampler}-{seed}.exr"
                    r = subprocess.run([str(a.pbrt), *common, "--seed", str(seed), "--outfile", str(out), *args,
                                        str(scene)],
                                       capture_output=True, text=True)
                    if r.returncode != 0:
                        sys.exit(r.stderr)
                    images[sampler].append(read_rgb(out))
                    h = read_header(out)
                    cpu[sampler].append(float(h["renderCPUSeconds"]))
                    if sampler.startswith("guided"):
                        prepass.setdefault(sampler, []).append(float(h["wavelengthGuidingCPUSeconds"]))
                        guide_bytes[sampler] = int(h["wavelengthGuidingBytes"])
                    if sampler == "guided" and seed == 1:
                        index = table_index(out)
                        shares = table_shares(out.with_suffix(".guiding") / "clusters.csv")
                        print(f"{name}: guided with {h['wavelengthGuidingTables']} tables, "
                              f"{h['wavelengthGuidingKinds']} kinds, pre-pass "
                              f"{h['wavelengthGuidingCPUSeconds']:.3f} s CPU", file=sys.stderr)
            if a.keep:
                shutil.copytree(tmp, a.keep / name, dirs_exist_ok=True,
                                ignore=shutil.ignore_patterns(*(f"{n}*" for n in a.scenes if n != name)))
            # The lit pixels of the mean of every image (lamps seen directly left out, as the
            # benchmark does).
            mean = np.mean([im for ims in images.values() for im in ims], axis=0)
            mask = lit_pixels(mean)
            # Each sampler's ΔE00 map of each seed pair, for the image's error, the pictures and
            # the per-table errors alike.
            maps = {sampler: [_delta_e(rgb_to_lab(ims[2 * i]), rgb_to_lab(ims[2 * i + 1])) for i in range(a.pairs)]
                    for sampler, ims in images.items()}
            if a.pictures:
                pictures(a.pictures, name, mean, maps, index, mask)
            if a.per_table:
                per_table_rows += per_table(name, a, maps, index, mask, shares)
            result, mean_de = {}, {}
            for sampler, pairs in maps.items():
                de2 = [float(np.mean(m[mask] ** 2) / 2) for m in pairs]
                result[sampler] = (np.mean(de2), np.std(de2, ddof=1) / np.sqrt(a.pairs) if a.pairs > 1 else np.nan,
                                   float(np.mean(cpu[sampler])))
                # The mean ΔE00 of a pair over sqrt(2): one image's mean error where the noise
                # dominates; it falls as spp^-1/2, so equal time takes the slope 1/2.
                mean_de[sampler] = float(np.mean([np.mean(m[mask]) for m in pairs])) / np.sqrt(2)
            e_em, _, t_em = result["emission"]
            e_gd, _, t_gd = result["guided"]
            floor = result["floor"][0] if "floor" in result else np.nan
            for sampler, (de2, se, t) in result.items():
                rows.append({"scene": name, "sampler": sampler, "spp": a.spp, "size": f"{a.size[0]}x{a.size[1]}",
                             "pairs": a.pairs, "de2": f"{de2:.5g}", "de2_se": f"{se:.2g}", "cpu_s": f"{t:.3f}",
                             # the spread of the 2 x PAIRS renders' CPU seconds
                             "cpu_s_min": f"{min(cpu[sampler]):.3f}", "cpu_s_max": f"{max(cpu[sampler]):.3f}",
                             "de2_vs_emission_equal_spp": f"{de2 / e_em:.3f}",
                             "de2_vs_emission_equal_time": f"{equal_time_ratio(de2, t, e_em, t_em):.3f}",
                             "de2_vs_visible_equal_time": (f"{equal_time_ratio(de2, t, *result['visible'][::2]):.3f}"
                                                           if "visible" in result else ""),
                             "de2_vs_guided_equal_time": f"{equal_time_ratio(de2, t, e_gd, t_gd):.3f}",
                             "mean_de": f"{mean_de[sampler]:.4g}",
                             "mean_de_vs_emission_equal_time":
                                 f"{equal_time_ratio(mean_de[sampler], t, mean_de['emission'], t_em, 0.5):.3f}",
                             "mean_de_vs_guided_equal_time":
                                 f"{equal_time_ratio(mean_de[sampler], t, mean_de['guided'], t_gd, 0.5):.3f}",
                             # the share of emission's error above the floor that is left
                             "above_floor_vs_emission": f"{(de2 - floor) / (e_em - floor):.3f}" if "floor" in result else "",
                             "optimizer_s": (f"{optimizer_s:.1f}" if sampler == "guided-optimized" else
                                             f"{sum(routes[c][1] for c in a.choose_from):.1f}"
                                             if sampler in chosen else ""),
                             "colours": (a.colours if sampler == "guided-optimized" else
                                         "+".join(a.choose_from) if sampler in chosen else ""),
                             # choose-guiding's seconds (its renders of the scene, cached like the
                             # tables) and each table's choice
                             "choose_s": f"{chosen[sampler][1]:.1f}" if sampler in chosen else "",
                             "choices": chosen[sampler][2] if sampler in chosen else "",
                             # the pre-pass and the tables' share of the render's CPU time, and the
                             # guide's memory (tables + tile map) against the film's 32 bytes a pixel
                             "prepass_share": f"{np.mean(prepass[sampler]) / t:.4f}" if sampler in prepass else "",
                             "guide_vs_film_memory": (f"{guide_bytes[sampler] / (32 * a.size[0] * a.size[1]):.4f}"
                                                      if sampler in guide_bytes else "")})
    w = csv.DictWriter(sys.stdout, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    for path, table in ((a.out, rows), (a.per_table, per_table_rows)):
        if path:
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(table[0]))
                w.writeheader()
                w.writerows(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
