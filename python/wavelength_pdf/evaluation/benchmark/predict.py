"""Does the objective predict the image? (docs/benchmark.md)

For every job of a finished benchmark (its ``results.csv`` and the tables it rendered with,
``OUT/tables/``), every prediction of :mod:`wavelength_pdf.predict` is computed for the table
of each row under the job's lamp, at the job's spp and pixel sampler; the predicted ratio of
a row to the optimized table is set beside the measured one (``de2`` of the row over ``de2``
of the table), and the agreement is summarised by Spearman's rank correlation over the
(job, row) pairs and by the spread of log(predicted / measured).

The predictions see the lamp on a white surface (``colours='colorchecker'``: the ColorChecker
jobs see its 24 patches). ``+floor`` variants add the path noise the benchmark measured (the
``floor`` row: the ``spd`` table with 8 wavelengths per path): predicted de2 of a row =
s * prediction + floor. The scale s turns the white surface's units into the image's; it is
fitted, for each job, on the *other* jobs of its scene, pixel sampler and spp (leave one job
out: no job's own measurements enter its prediction besides its floor), as the median of
(de2 - floor) / prediction over their rows; scenes with a single job per pixel sampler (their
own lamps) take it from the other jobs of their regime.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from wavelength_pdf.evaluation.benchmark import grid as G

#: The rows compared with the optimized table: the simple samplers, then the others the
#: benchmark renders with a table (the acceptance figure is over the simple ones).
COMPARED = (*G.SIMPLE, "start", "reference", G.SCENE_COLOURS)
TABLE = "optimized"
#: The two regimes: the ColorChecker (patches lit directly) and every other scene.
REGIMES = ("colorchecker", "scenes")
#: The predictions of :mod:`wavelength_pdf.predict` evaluated (``+floor`` variants are added).
CANDIDATES = ("J", "stratified", "stratified-de", "covariance", "covariance-lab")
FLOORED = ("stratified+floor", "stratified-de+floor", "covariance+floor")
LO, HI = 380.0, 780.0


def regime(scene: str) -> str:
    return REGIMES[0] if scene == "colorchecker" else REGIMES[1]


@dataclass
class JobInputs:
    """What the predictions of one job need: its lamp's spectrum source and row tables."""

    job: str
    scene: str
    lamp: str
    pixel_sampler: str
    #: row -> table file
    tables: dict[str, Path] = field(default_factory=dict)
    #: the lamp's spectrum spec (design §7), or for own-lamp scenes the spd table it is read from
    spectrum: str = ""


def read_results(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["spp"] = int(r["spp"])
        for k in ("de2",):
            r[k] = float(r[k])
    return rows


def plan(results: Sequence[dict], out: Path, shared: Path) -> tuple[list[JobInputs], list[str]]:
    """Each job's inputs, and what is missing (files named; nothing read yet)."""
    jobs: dict[str, JobInputs] = {}
    missing: list[str] = []
    for r in results:
        j = jobs.get(r["job"])
        if j is None:
            j = jobs[r["job"]] = JobInputs(r["job"], r["scene"], r["lamp"], r["pixel_sampler"])
            folder = out / "tables" / (f"own-{r['scene']}" if r["lamp"] == "own" else r["lamp"])
            if r["lamp"] == "own":
                j.spectrum = str(folder / "spd.csv")
                if not Path(j.spectrum).is_file():
                    missing.append(f"{j.job}: {j.spectrum} (the scene's emission, as its spd table)")
            elif r["lamp"] in G.LAMPS:
                lamp = G.LAMPS[r["lamp"]]
                j.spectrum = lamp.spec(shared)
                if not lamp.available(shared):
                    missing.append(f"{j.job}: lamp spectrum {j.spectrum}")
            else:
                missing.append(f"{j.job}: lamp {r['lamp']!r} is not one of the benchmark's")
        row = r["row"]
        if row in j.tables or row not in (*COMPARED, TABLE):
            continue
        if row == "reference":
            ref = G.LAMPS[r["lamp"]].reference if r["lamp"] in G.LAMPS else None
            path = shared / "tables" / "reference-4x81" / f"{ref}.csv"
        elif row == G.SCENE_COLOURS:
            path = out / "jobs" / r["scene"] / r["lamp"] / r["pixel_sampler"] / f"{row}.csv"
        else:
            path = out / "tables" / (f"own-{r['scene']}" if r["lamp"] == "own" else r["lamp"]) / f"{row}.csv"
        if path.is_file():
            j.tables[row] = path
        else:
            missing.append(f"{j.job}: the {row} table {path}")
    return list(jobs.values()), missing


def spectrum_of(j: JobInputs):
    """The lamp's spectrum; for an own-lamp scene, its total emission recovered from the
    scene's ``spd`` table: that table's mixture (1/4) sum_k p_k is the emission's shape
    exactly wherever it is linear between the table's nodes (design §1.7), and reading it
    back needs no renderer."""
    from wavelength_pdf.spectra import Spectrum, load_spectrum
    from wavelength_pdf.table import read_table

    if j.lamp != "own":
        return load_spectrum(j.spectrum, lo=LO, hi=HI)
    t = read_table(j.spectrum)
    return Spectrum(f"{j.scene}-whole-scene", f"{j.spectrum} (mixture)", np.asarray(t.grid, np.float64),
                    np.asarray(t.pdfs, np.float64).sum(axis=0))


#: What the lamp lights in the predictions: a white surface; on the ColorChecker jobs its 24
#: patches (white elsewhere); every job's own scene colours (``pbrt --material-reflectances``
#: on the job's scene copy, design §5.6; white where the scene has no diffuse colours); or
#: every lit pixel of the job's image, each with its own spectrum from one render of the scene
#: under a flat lamp (``pixels``, :mod:`.transfer`: colours, light paths and exposure as the
#: image has them, in the image's units).
COLOURS = ("white", "colorchecker", "scene", "pixels")
#: The candidates that ``pixels`` computes (the linearised ones: exact per pixel from one
#: tabulation, where the Monte Carlo and J would need one per pixel).
PIXEL_CANDIDATES = ("covariance", "covariance-lab")


def predict_jobs(results: Sequence[dict], jobs: Sequence[JobInputs], spps: Sequence[int] = (16, 64),
                 candidates: Sequence[str] = CANDIDATES, colours: str = "white",
                 say: Callable[[str], None] = lambda m: None, out: Path | None = None,
                 pbrt: Path | None = None, spread: bool = False, net: bool = False) -> list[dict]:
    """One record per (job, spp, row incl. the table): the measured de2 and floor, and each
    candidate's prediction (white-surface units). C(u) is tabulated once per lamp, table and
    colour set, and shared by every job and spp that uses it. ``colours`` is one of
    :data:`COLOURS`; ``scene`` reads each job's scene copy under ``out`` with ``pbrt``;
    ``spread`` (``pixels`` only): each pixel's spread in place of its incoherence
    (:func:`wavelength_pdf.evaluation.transfer.spread`); ``net`` (with it): the images were
    rendered with ``pbrt --wavelength-net``, which stratifies the spread between a pixel's
    cells (:func:`wavelength_pdf.predict.pixel_de2`)."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.reflectances import colorchecker, colours_label, load_reflectances
    from wavelength_pdf.spectra import SpectrumError
    from wavelength_pdf.table import read_table

    if colours not in COLOURS:
        raise ValueError(f"colours must be one of {COLOURS}, not {colours!r}")
    if colours in ("scene", "pixels") and out is None:
        raise ValueError(f"colours {colours!r} needs the benchmark's folder (out)")
    if spread and colours != "pixels":
        raise ValueError(f"spread is a property of the pixels (colours 'pixels'), not of colours {colours!r}")
    if net and not spread:
        raise ValueError("net models the spread's cells: give spread too")
    if colours == "pixels" and set(candidates) - set(PIXEL_CANDIDATES):
        raise ValueError(f"colours 'pixels' computes only {', '.join(PIXEL_CANDIDATES)}, not "
                         f"{', '.join(sorted(set(candidates) - set(PIXEL_CANDIDATES)))}")
    meas = {(r["job"], r["row"], r["spp"]): r for r in results}
    cache: dict[tuple, object] = {}
    spectra: dict[str, object] = {}
    by_scene: dict[str, object] = {}
    refl = colorchecker(LO, HI) if colours == "colorchecker" else None
    recs = []
    for n, j in enumerate(jobs):
        say(f"predict: {n + 1}/{len(jobs)} {j.job}")
        use_refl = refl if (refl is not None and j.scene == "colorchecker") else None
        if colours == "scene":
            if j.scene not in by_scene:  # a scene's materials do not depend on its lamp
                try:
                    by_scene[j.scene] = load_reflectances("scene", scene=out / "jobs" / j.job / "scene.pbrt",
                                                          lo=LO, hi=HI, pbrt=pbrt)
                except SpectrumError:  # no diffuse colours (the glass of water): the white surface
                    by_scene[j.scene] = None
            use_refl = by_scene[j.scene]
        if j.spectrum not in spectra:
            spectra[j.spectrum] = spectrum_of(j)
        if colours == "pixels":
            recs += _pixel_records(j, meas, spps, candidates, by_scene, cache, spectra[j.spectrum], out, pbrt,
                                   spread, net)
            continue
        for row, path in j.tables.items():
            key = (str(path), j.spectrum, j.scene if colours == "scene" else colours_label(use_refl))
            if key not in cache:
                cache[key] = P.path_colours(read_table(path), spectra[j.spectrum], use_refl)
            pc = cache[key]
            for spp in spps:
                rec = _record(j, row, spp, meas)
                if rec is None:
                    continue
                for c in candidates:
                    rec[c] = P.CANDIDATES[c](pc, spp, j.pixel_sampler)
                recs.append(rec)
    return recs


def _record(j: JobInputs, row: str, spp: int, meas: dict) -> dict | None:
    """A prediction record's measured part (None where the row was not rendered at spp)."""
    m = meas.get((j.job, row, spp))
    if m is None:
        return None
    return {"job": j.job, "regime": regime(j.scene), "scene": j.scene, "lamp": j.lamp,
            "pixel_sampler": j.pixel_sampler, "spp": spp, "row": row, "de2": m["de2"],
            "floor": floor_of(meas, j.job, spp)}


def scene_transfer(scene: str, out: Path, shared: Path = G.SHARED, pbrt: Path | None = None,
                   spp: int | None = None, spread: bool = False, net: bool = False):
    """The transfer (:mod:`wavelength_pdf.evaluation.transfer`) of a benchmark scene at its
    benchmark size, in ``out/transfer/SCENE`` (rendered once), with each pixel's spread if
    ``spread``, and its cells if ``net`` (:func:`.transfer.of_file`)."""
    from wavelength_pdf.evaluation import transfer

    spec = G.SCENES[scene]
    if spec.own_lamps:
        raise ValueError(f"{scene}: lit by its own lamps of several kinds, whose pixel spectra are not "
                         "one lamp times the scene's transfer")
    folder = Path(out) / "transfer" / scene
    source = spec.path(shared)
    if spec.water:
        from wavelength_pdf.evaluation.glass_of_water import with_water

        source = with_water(source, folder / "with-water" / "scene.pbrt")
    return transfer.of_file(source, folder, spec.resolution, pbrt, spp or transfer.SPP, with_spread=spread,
                            net=net)


def _pixel_records(j: JobInputs, meas: dict, spps, candidates, by_scene: dict, cache: dict, spectrum,
                   out: Path, pbrt: Path | None, spread: bool = False, net: bool = False) -> list[dict]:
    """``predict_jobs``' records of one job with ``colours='pixels'``: each prediction is the
    mean over the image's lit pixels of that pixel's own (:func:`wavelength_pdf.predict.pixel_de2`)."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.table import read_table

    if j.scene not in by_scene:
        by_scene[j.scene] = scene_transfer(j.scene, out, pbrt=pbrt, spread=spread, net=net)
    tr = by_scene[j.scene]
    basis = P.hat_basis(tr.centres, LO, HI)
    recs = []
    path_noise: dict[int, float] = {}
    for row, path in j.tables.items():
        key = (str(path), j.spectrum, "pixels", tuple(tr.centres))
        if key not in cache:
            table = read_table(path)
            cache[key] = (P.basis_path_colours(table, spectrum, basis),
                          P.one_wavelength_covariance(table, spectrum, basis))
        pc, one = cache[key]
        for spp in spps:
            rec = _record(j, row, spp, meas)
            if rec is None:
                continue
            if spp not in path_noise:  # the same for every row: the pixels' colours and paths
                path_noise[spp] = float(np.mean(P.path_de2(tr.t @ pc.target, tr.incoherence, spp)))
            rec["path"] = path_noise[spp]
            for c in candidates:
                metric = "lab" if c == "covariance-lab" else "de2000"
                rec[c] = float(np.mean(P.pixel_de2(pc, tr.t, spp, j.pixel_sampler, metric, incoherence=tr.incoherence,
                                                   terminated=tr.terminated, one_wavelength=one,
                                                   spread=tr.spread, cells=tr.cells)))
            recs.append(rec)
    return recs


def floor_of(meas: dict, job: str, spp: int) -> float:
    """The job's measured floor (de2 of the ``floor`` row) at spp; where it was rendered only
    at fewer spp (results of a lamp sweep run before its floor was rendered at 64 spp too),
    scaled by their ratio (path noise of independent paths falls as 1/spp; on the Cornell box
    with ``--wavelength-net`` the 16-spp floor so scaled was 1.13 times too low at 64 spp,
    docs/benchmark.md)."""
    f = meas.get((job, G.FLOOR, spp))
    if f is not None:
        return f["de2"]
    lower = sorted(n for (jb, row, n) in meas if jb == job and row == G.FLOOR and n < spp)
    return meas[(job, G.FLOOR, lower[-1])]["de2"] * lower[-1] / spp if lower else float("nan")


def add_floor(records: list[dict], bases: Sequence[str] = ("stratified", "stratified-de", "covariance"),
              fit: bool = True) -> None:
    """The ``+floor`` variants: s * prediction + floor, s fitted leaving the job out (module
    docstring); ``fit=False``: s = 1, for predictions already in the image's units
    (``colours='pixels'``)."""
    if not fit:
        for base in bases:
            for r in records:
                if base in r:
                    r[f"{base}+floor"] = r[base] + r["floor"]
                    if "path" in r:  # the floor predicted from the pixels (``colours='pixels'``)
                        r[f"{base}+path"] = r[base] + r["path"]
        return
    def groups(r):
        return (r["scene"], r["pixel_sampler"], r["spp"]), (r["regime"], r["pixel_sampler"], r["spp"])

    for base in bases:
        if not records or base not in records[0]:
            continue
        logs: dict[tuple, list[tuple[str, float]]] = {}
        for r in records:
            above = r["de2"] - r["floor"]
            if above > 0 and r[base] > 0 and math.isfinite(above):
                for g in groups(r):
                    logs.setdefault(g, []).append((r["job"], math.log(above / r[base])))
        for r in records:
            s = float("nan")
            for g in groups(r):
                others = [v for jb, v in logs.get(g, []) if jb != r["job"]]
                if len({jb for jb, _ in logs.get(g, []) if jb != r["job"]}) >= 2:
                    s = math.exp(float(np.median(others)))
                    break
            r[f"{base}+floor"] = s * r[base] + r["floor"]


def pairs(records: Sequence[dict], candidates: Sequence[str]) -> list[dict]:
    """One pair per (job, spp, compared row): measured and predicted ratio row / table."""
    table = {(r["job"], r["spp"]): r for r in records if r["row"] == TABLE}
    out = []
    for r in records:
        t = table.get((r["job"], r["spp"]))
        if r["row"] == TABLE or t is None:
            continue
        p = {k: r[k] for k in ("job", "regime", "scene", "lamp", "pixel_sampler", "spp", "row")}
        p["measured"] = r["de2"] / t["de2"]
        for c in candidates:
            p[c] = r[c] / t[c] if t[c] > 0 else float("nan")
        out.append(p)
    return out


def summary(prs: Sequence[dict], candidates: Sequence[str], rows: Sequence[str] = G.SIMPLE) -> list[dict]:
    """Spearman's rank correlation and the spread of log(predicted / measured) per candidate,
    spp and regime (and over both), over the pairs of ``rows``."""
    from scipy.stats import spearmanr

    out = []
    for spp in sorted({p["spp"] for p in prs}):
        for reg in ("all", *REGIMES):
            sel = [p for p in prs if p["spp"] == spp and p["row"] in rows and (reg == "all" or p["regime"] == reg)]
            for c in candidates:
                ok = [p for p in sel if p[c] > 0 and p["measured"] > 0 and math.isfinite(p[c])]
                if len(ok) < 3:
                    continue
                meas = np.array([p["measured"] for p in ok])
                pred = np.array([p[c] for p in ok])
                rho = float(spearmanr(pred, meas).statistic)
                d = np.log10(pred / meas)
                out.append({"candidate": c, "spp": spp, "regime": reg, "pairs": len(ok), "spearman": rho,
                            "log10_median": float(np.median(d)), "log10_p05": float(np.quantile(d, 0.05)),
                            "log10_p95": float(np.quantile(d, 0.95))})
    return out


def choices(records: Sequence[dict], candidate: str, rows: Sequence[str] = (*G.SIMPLE, TABLE),
            margin: float = 1.1) -> list[dict]:
    """Per job and spp, the row of ``rows`` that ``candidate`` predicts best (the table, or a
    simple sampler where the prediction says one beats it: the image's own health rule,
    never worse than the best simple sampler), with its measured de2 beside the table's and
    the best simple sampler's (chosen after the fact). ``worse`` marks a measured error above
    ``margin`` times the best simple sampler's, for the chosen row and for the table."""
    by = {}
    for r in records:
        if r["row"] in rows and math.isfinite(r.get(candidate, float("nan"))):
            by.setdefault((r["job"], r["spp"]), {})[r["row"]] = r
    out = []
    for (job, spp), rs in sorted(by.items()):
        if TABLE not in rs or not any(row in rs for row in G.SIMPLE):
            continue
        pick = min(rs, key=lambda row: rs[row][candidate])
        best = min(rs[row]["de2"] for row in G.SIMPLE if row in rs)
        out.append({"job": job, "scene": rs[pick]["scene"], "lamp": rs[pick]["lamp"], "spp": spp, "chosen": pick,
                    "de2_chosen": rs[pick]["de2"], "de2_table": rs[TABLE]["de2"], "de2_best_simple": best,
                    "chosen_worse": rs[pick]["de2"] > margin * best, "table_worse": rs[TABLE]["de2"] > margin * best})
    return out


def choices_markdown(ch: Sequence[dict]) -> str:
    """Per spp: how often the table and the chosen row lose to the best simple sampler by
    more than the margin, and the chosen row's error over the table's."""
    lines = ["| spp | jobs | table worse than the best simple sampler by > 10 % | chosen row so | "
             "chosen / table (median, min-max) | chose a simple sampler |", "|---|---|---|---|---|---|"]
    for spp in sorted({c["spp"] for c in ch}):
        sel = [c for c in ch if c["spp"] == spp]
        r = np.array([c["de2_chosen"] / c["de2_table"] for c in sel])
        lines.append(f"| {spp} | {len(sel)} | {sum(c['table_worse'] for c in sel)} | "
                     f"{sum(c['chosen_worse'] for c in sel)} | {np.median(r):.3f} ({r.min():.2f}-{r.max():.2f}) | "
                     f"{sum(c['chosen'] != TABLE for c in sel)} |")
    return "\n".join(lines)


def write_csv(path: Path, prs: Sequence[dict], candidates: Sequence[str]) -> None:
    cols = ["job", "regime", "scene", "lamp", "pixel_sampler", "spp", "row", "measured", *candidates]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for p in prs:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in p.items()})


def read_pairs(path: Path) -> tuple[list[dict], list[str]]:
    """The pairs and candidates of a ``prediction.csv`` that :func:`write_csv` wrote."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        cols = list(reader.fieldnames or [])
        if "measured" not in cols:
            raise ValueError(f"{path}: not a prediction.csv (no 'measured' column)")
        cands = cols[cols.index("measured") + 1:]
        prs = []
        for line, r in enumerate(reader, start=2):
            try:
                p = {**r, "spp": int(r["spp"]), **{k: float(r[k]) for k in ("measured", *cands)}}
            except (TypeError, ValueError) as e:
                raise ValueError(f"{path}:{line}: {e}") from None
            prs.append(p)
    return prs, cands


def plot(path: Path, prs: Sequence[dict], candidates: Sequence[str], rows: Sequence[str] = G.SIMPLE) -> None:
    """Predicted against measured ratio (row / table), log-log, one colour per candidate, a
    panel per spp."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spps = sorted({p["spp"] for p in prs})
    fig, axes = plt.subplots(1, len(spps), figsize=(5.5 * len(spps), 5.2), squeeze=False)
    for ax, spp in zip(axes[0], spps):
        sel = [p for p in prs if p["spp"] == spp and p["row"] in rows]
        lo, hi = 1e9, 1e-9
        for i, c in enumerate(candidates):
            ok = [p for p in sel if p[c] > 0 and math.isfinite(p[c]) and p["measured"] > 0]
            x = np.array([p["measured"] for p in ok])
            y = np.array([p[c] for p in ok])
            ax.scatter(x, y, s=8, alpha=0.55, color=f"C{i}", label=c, edgecolors="none")
            if ok:
                lo, hi = min(lo, x.min(), y.min()), max(hi, x.max(), y.max())
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("measured de2 ratio, sampler / optimized table")
        ax.set_ylabel("predicted ratio")
        ax.set_title(f"{spp} spp, simple samplers vs the table")
        ax.legend(fontsize=8, markerscale=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(summ: Sequence[dict]) -> str:
    """The Spearman table: a row per candidate, a column per regime and spp."""
    cands = list(dict.fromkeys(s["candidate"] for s in summ))
    get = {(s["candidate"], s["spp"], s["regime"]): s for s in summ}
    cols = [(spp, reg) for spp in sorted({s["spp"] for s in summ}) for reg in ("all", *REGIMES)
            if any((c, spp, reg) in get for c in cands)]
    head = "| prediction | " + " | ".join(f"{reg}, {spp} spp" for spp, reg in cols) + " |\n|---|" + "---|" * len(cols)
    lines = [head]
    for c in cands:
        cells = []
        for spp, reg in cols:
            s = get.get((c, spp, reg))
            cells.append("–" if s is None else f"{s['spearman']:.2f} ({s['log10_median']:+.1f}; "
                                               f"{s['log10_p05']:+.1f}..{s['log10_p95']:+.1f})")
        lines.append(f"| {c} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
