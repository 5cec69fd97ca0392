#!/usr/bin/env python3
"""Benchmarks of the Mitsuba 3 plugin (wavelength_pdf.mitsuba) on the project's Cornell box.

Three measurements, each printed as figures measured in this run:

- ``--cost`` (default): time per sample in llvm_ad_spectral with the table against Mitsuba's
  default sampling; renders alternate (default, table, default, ...) so that a change in the
  machine's load hits both; the first render of each (Dr.Jit compiles its kernel) is left out.
  Prints the ratio of the median times, the median of the pairs' ratios and the ratio of the
  fastest runs (on a shared machine other jobs only add time, so the fastest runs are the
  least disturbed).
- ``--error``: the mean CIEDE2000 at 64 spp against a high-spp ground truth for uniform,
  the renderer's default and the table, with Mitsuba (llvm_ad_spectral, scenes/cornell-box/
  scene.xml) and with this project's pbrt (scenes/cornell-box/scene.pbrt) on the same lamp
  and table; prints both factors (default / table, uniform / table).
- ``--unbiased``: image means of the table and of Mitsuba's default at high spp, per channel,
  with their standard errors (seed-to-seed), and the relative difference; then the CIEDE2000
  between the two mean images per block (a quarter of the image side), beside what the
  seed-to-seed noise alone predicts. Mitsuba's default
  has a per-path relative standard deviation of 15-60 under a line spectrum, so a 0.5 %
  check takes about 1e8 paths per method.
- ``--sampler-cost``: the wavelength sampler alone in llvm_ad_spectral, nanoseconds of CPU time
  per path (4M paths a round, ``dr.sync_thread`` after each, median and fastest of
  ``--runs`` rounds, the first left out): the table's ``sample_four`` (its wavelengths and
  the weights 1 / mixture pdf) against Mitsuba's ``sample_rgb_spectrum`` on the four
  shifted lanes, alternating.
- ``--direct``: the same comparison on the lamp seen directly (a constant environment), which
  tests the wavelength sampler alone, without light transport, to a few hundredths of a percent.

Usage::

    .venv/bin/python scripts/bench_mitsuba_table.py [--cost] [--error] [--unbiased] [--direct] [--sampler-cost]
        [--spectrum SPD] [--table CSV] [--resolution N] [--spp N] [--runs N]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SCENE_XML = REPO / "scenes" / "cornell-box" / "scene.xml"
SCENE_PBRT = REPO / "scenes" / "cornell-box" / "scene.pbrt"
TRIBAND = REPO / "spectra" / "tri-band-fluorescent.spd"
TRIBAND_TABLE = REPO / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
VARIANT = "llvm_ad_spectral"


def cost(spectrum, table: Path, res: int, spp: int, runs: int, out: Path) -> None:
    from wavelength_pdf.evaluation import render_mitsuba as rm

    params = rm.scene_params(SCENE_XML, spectrum, 380.0, 780.0, (res, res))
    xml = {m: rm.write_variant(SCENE_XML, out / f"cost-{m}.xml", m, table, 380.0, 780.0) for m in ("visible", "table")}
    times: dict[str, list[float]] = {"visible": [], "table": []}
    cpu: dict[str, list[float]] = {"visible": [], "table": []}
    for k in range(runs + 1):
        for m in ("visible", "table") if k % 2 == 0 else ("table", "visible"):
            start, start_cpu = time.perf_counter(), time.process_time()
            rm.render_image(xml[m], params, spp, 100 + k, VARIANT)
            if k > 0:  # the first round compiles the kernels
                times[m].append(time.perf_counter() - start)
                cpu[m].append(time.process_time() - start_cpu)
    paths = res * res * spp
    for m, ts in times.items():
        print(f"{m:8s} median {statistics.median(ts):.3f} s wall, {statistics.median(cpu[m]):.3f} s CPU "
              f"({paths / statistics.median(ts) / 1e6:.2f} M paths/s; wall runs {', '.join(f'{t:.3f}' for t in ts)})")
    for what, d in (("wall", times), ("CPU (all threads; less sensitive to other jobs)", cpu)):
        ratio = statistics.median(d["table"]) / statistics.median(d["visible"])
        pairs = statistics.median([t / v for t, v in zip(d["table"], d["visible"])])
        fastest = min(d["table"]) / min(d["visible"])  # other jobs only ever add time
        print(f"time per sample, table / Mitsuba default, {what}: {ratio:.3f} (median of pairs {pairs:.3f}, "
              f"fastest runs {fastest:.3f})")
    print(f"({res}x{res}, {spp} spp, {runs} alternating runs, {VARIANT}, scene loading included)")


def error(spectrum_spec: str, table: Path, res: int, spp: int, truth_spp: int, out: Path) -> None:
    from wavelength_pdf.evaluation import protocol, render_mitsuba
    from wavelength_pdf.spectra import load_spectrum

    spectrum = load_spectrum(spectrum_spec)
    config = protocol.Config(spp=(spp,), truth_spp=truth_spp, resolution=(res, res), seeds=2)
    found = {}
    for name, run, scene in (("mitsuba", render_mitsuba.evaluate, SCENE_XML), ("pbrt", protocol.evaluate, SCENE_PBRT)):
        ev = run(scene, spectrum, out / name, config, table=table)
        found[name] = {r.method: r for r in ev.rows}
    for name, rows in found.items():
        u, v, t = rows["uniform"], rows["visible"], rows["table"]
        print(f"{name:8s} {spp} spp mean CIEDE2000: uniform {u.mean:.3f}, default {v.mean:.3f}, table {t.mean:.3f}; "
              f"default/table {v.mean / t.mean:.2f}, uniform/table {u.mean / t.mean:.2f} "
              f"(time table/default {t.seconds / v.seconds:.2f})")


def unbiased(spectrum, table: Path, res: int, spp: int, runs: int, out: Path, sampler: str,
             table_runs: int | None = None, variant: str = VARIANT, seed: int = 500) -> None:
    """Image means of the table and of the default; ``table_runs`` (default ``runs``) lets the
    table, whose images are far less noisy, take fewer seeds than the default, whose noise
    sets the difference's standard error."""
    from wavelength_pdf.evaluation import render_mitsuba as rm

    params = rm.scene_params(SCENE_XML, spectrum, 380.0, 780.0, (res, res))
    images = {}
    n_runs = {"table": table_runs or runs, "visible": runs}
    for m in ("table", "visible"):
        xml = rm.write_variant(SCENE_XML, out / f"unbiased-{m}.xml", m, table, 380.0, 780.0, sampler=sampler)
        images[m] = np.array([np.asarray(rm.render_image(xml, params, spp, seed + k, variant), dtype=np.float64)[..., :3]
                              for k in range(n_runs[m])])
    np.savez_compressed(out / f"unbiased-{variant}-seed{seed}.npz", **images)  # per-seed images, for a second look
    for m, n in n_runs.items():
        print(f"{m}: {n} x {res}x{res} x {spp} spp ({n * res * res * spp / 1e6:.0f} M paths, {sampler}, {variant})")
    _print_means({m: a.mean(axis=(1, 2)) for m, a in images.items()})
    _print_block_delta_e(images, block=max(1, res // 4))


def _print_block_delta_e(images: dict, block: int, draws: int = 4000) -> None:
    """CIEDE2000 between the table's and the default's mean images per block of block x block
    pixels, beside what seed-to-seed noise alone predicts when both have the same expectation:
    a parametric bootstrap that adds to the pooled block means a normal difference with the
    two methods' per-block RGB covariances (over seeds, divided by the number of seeds)."""
    from wavelength_pdf.evaluation.metrics import delta_e_map

    def blocks(a):  # (seeds, h, w, 3) -> (seeds, blocks, 3)
        s, h, w, _ = a.shape
        a = a[:, : h // block * block, : w // block * block]
        return a.reshape(s, h // block, block, w // block, block, 3).mean(axis=(2, 4)).reshape(s, -1, 3)

    bt, bv = blocks(images["table"]), blocks(images["visible"])
    mt, mv = bt.mean(0), bv.mean(0)
    observed = delta_e_map(mt, mv)

    def cov_of_mean(b):  # (blocks, 3, 3)
        d = b - b.mean(0)
        return np.einsum("sbi,sbj->bij", d, d) / (len(b) - 1) / len(b)

    cov = cov_of_mean(bt) + cov_of_mean(bv)
    chol = np.linalg.cholesky(cov + 1e-30 * np.eye(3))
    pooled = (mt * len(bt) + mv * len(bv)) / (len(bt) + len(bv))
    z = np.random.default_rng(1).standard_normal((draws, *pooled.shape))
    noisy = pooled + np.einsum("bij,dbj->dbi", chol, z)
    sim = delta_e_map(np.broadcast_to(pooled, noisy.shape), noisy)
    mean_q = np.quantile(sim.mean(1), [0.5, 0.95])
    max_q = np.quantile(sim.max(1), [0.5, 0.95])
    print(f"block CIEDE2000, table against default ({len(observed)} blocks of {block}x{block} px): "
          f"mean {observed.mean():.4f}, max {observed.max():.4f}; noise alone predicts mean {mean_q[0]:.4f} "
          f"(95th percentile {mean_q[1]:.4f}), max {max_q[0]:.4f} (95th percentile {max_q[1]:.4f}): "
          f"{'within' if observed.mean() <= mean_q[1] and observed.max() <= max_q[1] else 'OUTSIDE'} the noise")


def _print_means(means: dict) -> None:
    """Mean RGB of the table's and the default's per-seed image means, their standard
    errors, and the relative difference."""
    (mt, st), (mv, sv) = [(a.mean(0), a.std(0, ddof=1) / np.sqrt(len(a))) for a in (means["table"], means["visible"])]
    print(f"table   mean RGB {mt} +- {st}")
    print(f"default mean RGB {mv} +- {sv}")
    print(f"relative difference table/default - 1: {mt / mv - 1}  (+- {np.hypot(st, sv) / mv})")


def direct(spectrum, table: Path, spp: int, runs: int, variant: str = VARIANT) -> None:
    """The lamp seen directly (a constant environment filling a 64x64 view): the wavelength
    sampler alone, without light transport, so that the default's noise is small enough for
    a 0.05 % comparison. Image means of the table and of Mitsuba's default, per channel."""
    from wavelength_pdf.evaluation import render_mitsuba as rm

    mi = rm._import(variant)
    lam, val = rm.lamp_radiance(spectrum, 1.0, 380.0, 780.0)
    env = {"type": "constant", "radiance": {"type": "irregular", "wavelengths": ", ".join(f"{x:.10g}" for x in lam),
                                            "values": ", ".join(f"{x:.10g}" for x in val)}}
    means = {}
    for m in ("table", "visible"):
        sensor = {"type": "perspective", "fov": 10.0, "sampler": {"type": "independent", "sample_count": spp},
                  "film": {"type": "hdrfilm", "width": 64, "height": 64, "rfilter": {"type": "box"}}}
        if m == "table":
            sensor["srf"] = {"type": "wavelength_table", "filename": str(table)}
        scene = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2}, "sensor": sensor, "env": env})
        means[m] = np.array([np.asarray(mi.render(scene, seed=k), dtype=np.float64)[..., :3].mean(axis=(0, 1))
                             for k in range(runs)])
    print(f"lamp seen directly: {runs} x 64x64 x {spp} spp per method ({runs * 4096 * spp / 1e6:.0f} M paths, {variant})")
    _print_means(means)


def sampler_cost(table: Path, runs: int, paths: int = 1 << 22) -> None:
    """ns of CPU time per path of the table's sampler and of Mitsuba's default, alternating."""
    from wavelength_pdf.evaluation import render_mitsuba as rm
    from wavelength_pdf.mitsuba import TableSampler
    from wavelength_pdf.table import read_table

    mi = rm._import(VARIANT)
    import drjit as dr

    s = TableSampler(read_table(table), mi)
    u_host = np.random.default_rng(1).random(paths).astype(np.float32)

    def table_fn(u):
        lam, pdf = s.sample_four(mi.Float64(u))
        return sum(mi.Float(x) * mi.Float(dr.select(p > 0, dr.rcp(p), 0.0)) for x, p in zip(lam, pdf))

    def default_fn(u):
        lanes = [u + 0.25 * j for j in range(4)]  # what the sensor hands its srf: u + j/4, wrapped
        wl, w = mi.sample_rgb_spectrum(mi.Spectrum(*[x - dr.floor(x) for x in lanes]))
        return sum(wl[j] * w[j] for j in range(4))

    ns: dict[str, list[float]] = {"table": [], "default": []}
    u = mi.Float(u_host)
    for k in range(runs + 1):
        for name, fn in (("table", table_fn), ("default", default_fn)) if k % 2 == 0 else \
                (("default", default_fn), ("table", table_fn)):
            uu = u + 0.0  # a fresh input, so that nothing is reused from the last round
            dr.eval(uu)
            dr.sync_thread()
            start = time.process_time()
            out = fn(uu)
            dr.eval(out)
            dr.sync_thread()
            if k > 0:  # the first round compiles the kernels
                ns[name].append((time.process_time() - start) * 1e9 / paths)
    for name, v in ns.items():
        print(f"{name:8s} median {statistics.median(v):6.1f} ns per path, fastest {min(v):6.1f} "
              f"(rounds {', '.join(f'{x:.1f}' for x in v)})")
    print(f"({table.name}: {s.n} nodes, {s.n_merged} merged CDF values; {paths} paths a round, "
          f"{runs} rounds, {VARIANT}, CPU time of all threads)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cost", action="store_true")
    p.add_argument("--error", action="store_true")
    p.add_argument("--unbiased", action="store_true")
    p.add_argument("--sampler-cost", action="store_true",
                   help="the wavelength sampler alone: ns per path, table against Mitsuba's default")
    p.add_argument("--direct", action="store_true",
                   help="the lamp seen directly: the wavelength sampler alone, table against default")
    p.add_argument("--spectrum", default=str(TRIBAND))
    p.add_argument("--table", type=Path, default=TRIBAND_TABLE)
    p.add_argument("--resolution", type=int, default=None, help="image side (default: 128 cost, 64 error, 16 unbiased)")
    p.add_argument("--spp", type=int, default=None, help="spp (default: 64 cost and error, 4096 unbiased)")
    p.add_argument("--truth-spp", type=int, default=4096)
    p.add_argument("--runs", type=int, default=None, help="alternating runs (cost, default 5) or seeds (unbiased, 16)")
    p.add_argument("--table-runs", type=int, default=None,
                   help="seeds of the table in --unbiased (default --runs; its images are far less noisy)")
    p.add_argument("--variant", default=VARIANT, help=f"Mitsuba variant of --unbiased and --direct (default {VARIANT})")
    p.add_argument("--sampler", default="ldsampler",
                   help="Mitsuba sample generator of --unbiased (default ldsampler: randomly scrambled, so "
                        "unbiased, and less noisy than independent under line spectra)")
    p.add_argument("--seed", type=int, default=500,
                   help="first seed of --unbiased (seeds SEED, SEED+1, ...; another value gives an independent run)")
    p.add_argument("-o", "--outdir", type=Path, default=REPO / "out" / "bench-mitsuba")
    args = p.parse_args(argv)
    if not (args.cost or args.error or args.unbiased or args.direct or args.sampler_cost):
        args.cost = True
    import wavelength_pdf.mitsuba  # noqa: F401  (DRJIT_LIBLLVM_PATH before the llvm backend starts)
    from wavelength_pdf.spectra import load_spectrum
    from wavelength_pdf.table import read_table

    read_table(args.table)  # a bad table stops here
    spectrum = load_spectrum(args.spectrum)
    args.outdir.mkdir(parents=True, exist_ok=True)
    if args.cost:
        cost(spectrum, args.table, args.resolution or 128, args.spp or 64, args.runs or 5, args.outdir)
    if args.error:
        error(args.spectrum, args.table, args.resolution or 64, args.spp or 64, args.truth_spp, args.outdir)
    if args.unbiased:
        unbiased(spectrum, args.table, args.resolution or 16, args.spp or 4096, args.runs or 16, args.outdir,
                 args.sampler, args.table_runs, args.variant, args.seed)
    if args.sampler_cost:
        sampler_cost(args.table, args.runs or 7)
    if args.direct:
        direct(spectrum, args.table, args.spp or 1024, args.runs or 100, args.variant)
    return 0


if __name__ == "__main__":
    sys.exit(main())
