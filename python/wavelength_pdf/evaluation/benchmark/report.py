"""The benchmark's results: one CSV, a Markdown report and its plots (design §6.7).

Every ratio is a sampler's error divided by the optimized table's (above 1: the table is
better), at equal spp unless it says "equal time". The main measure is ``de2``, the mean
squared CIEDE2000 of one image from its seed pair (no reference involved, :mod:`.measures`).
"""
from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Sequence

import numpy as np

from wavelength_pdf.evaluation.benchmark import grid as G
from wavelength_pdf.evaluation.benchmark import measures as M

#: The measure the tables and the regime map use.
MAIN = "de2"
#: A table that beats the best simple sampler by this factor (in MAIN) "pays".
PAYS = 1.2

COLUMNS = ["job", "sweep", "scene", "lamp", "kind", "spiky", "pixel_sampler", "row", "spp",
           *M.MEASURES, "mse_rse", "bias_z", "cpu", "depth", "ratio_de2", "ratio_de", "ratio_mse",
           "share_removed_de2", "de2_lo", "truth_de", "truth_de2"]


def flatten(scores: Sequence[dict]) -> list[dict]:
    """One row per job, sampler and spp, with its ratios to the optimized table and its share
    of the removable error (relative to uniform, above the floor)."""
    out = []
    for s in scores:
        rows = s["rows"]
        for row, per in rows.items():
            for n, m in per.items():
                opt = (rows.get("optimized") or rows.get("start", {})).get(n)
                uni, flo = rows.get("uniform", {}).get(n), rows.get(G.FLOOR, {}).get(n)
                r = {"job": s["job"], "sweep": s["sweep"], "scene": s["scene"], "lamp": s["lamp"],
                     "kind": s["kind"], "spiky": s["spiky"], "pixel_sampler": s["pixel_sampler"], "row": row,
                     "spp": int(n), **{k: m.get(k) for k in (*M.MEASURES, "mse_rse", "bias_z", "cpu", "depth")},
                     "de2_lo": m.get("de2_lo", float("nan")),
                     "truth_de": s["truth_de"], "truth_de2": s["truth_de2"]}
                for k in ("de2", "de", "mse"):
                    r[f"ratio_{k}"] = m[k] / opt[k] if opt and opt[k] > 0 else float("nan")
                r["share_removed_de2"] = (M.removed_share(m["de2"], uni["de2"], flo["de2"])
                                          if uni and flo else float("nan"))
                out.append(r)
    return out


def write_csv(path: Path, rows: Sequence[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def _get(rows, job, row, spp):
    for r in rows:
        if r["job"] == job and r["row"] == row and r["spp"] == spp:
            return r
    return None


def _table(rows, job, spp):
    """The job's table row at spp: the optimized table, or the optimizer's start where the job
    has no optimized table (the suite's small grid)."""
    return _get(rows, job, "optimized", spp) or _get(rows, job, "start", spp)


def best_simple(rows: Sequence[dict], job: str, spp: int, measure: str = MAIN) -> tuple[str, float]:
    """The simple sampler with the least error on a job at spp, and that error."""
    cands = [(r[measure], r["row"]) for r in rows if r["job"] == job and r["spp"] == spp and r["row"] in G.SIMPLE]
    e, name = min(cands)
    return name, e


def jobs_of(rows: Sequence[dict], sweep: str | None = None, pixel_sampler: str | None = None) -> list[str]:
    seen = []
    for r in rows:
        if (sweep is None or sweep in r["sweep"].split("+")) and (pixel_sampler is None or r["pixel_sampler"] == pixel_sampler):
            if r["job"] not in seen:
                seen.append(r["job"])
    return seen


def gain(rows: Sequence[dict], job: str, spp: int, measure: str = MAIN) -> float:
    """Best simple sampler's error over the optimized table's (nan without a table)."""
    opt = _table(rows, job, spp)
    if opt is None or not opt[measure] > 0:
        return float("nan")
    return best_simple(rows, job, spp, measure)[1] / opt[measure]


def _fmt(x: float, digits: int = 2) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{x:.{digits}f}"


def ratio_table(rows: Sequence[dict], jobs: Sequence[str], spp: int, measure: str = MAIN,
                extra: Sequence[str] = (G.PIXEL, "reference", *G.COLOUR_ROWS, G.GENERIC_COLOURS,
                                        G.BUILTIN)) -> str:
    """Markdown: per job, each sampler's error over the table's, the best simple one, the
    table's share of the removable error and the floor's share of the table's error."""
    cols = [c for c in (*G.SIMPLE, "start", *extra) if any(_get(rows, j, c, spp) for j in jobs)]
    head = ("| job | " + " | ".join(cols) + " | best simple / table | table removes | floor / table |\n|"
            + "---|" * (len(cols) + 4) + "\n")
    lines = []
    for j in jobs:
        opt = _table(rows, j, spp)
        if opt is None:
            continue
        cells = []
        for c in cols:
            r = _get(rows, j, c, spp)
            cells.append(_fmt(r[measure] / opt[measure]) if r and opt[measure] > 0 else "–")
        name, e = best_simple(rows, j, spp, measure)
        flo = _get(rows, j, G.FLOOR, spp)
        floor = "–"
        if flo:
            lo = flo.get(f"{measure}_lo", float("nan"))
            floor = (f"{_fmt(lo / opt[measure])}-" if math.isfinite(lo) else "") + _fmt(flo[measure] / opt[measure])
        lines.append(f"| {j} | " + " | ".join(cells) + f" | **{_fmt(e / opt[measure])}** ({name}) | "
                     f"{_fmt(100 * opt['share_removed_de2'], 0)} % | {floor} |")
    return head + "\n".join(lines) + "\n"


def equal_time(rows: Sequence[dict], timing: dict, spp: int, measure: str = MAIN) -> list[dict]:
    """Per timed job and row: CPU seconds and the error ratio to the table at equal CPU time
    (the error's local slope over spp from the job's own curve)."""
    out = []
    for (job, row), t in timing.items():
        r, opt = _get(rows, job, row, spp), _table(rows, job, spp)
        t_opt = timing.get((job, opt["row"])) if opt else None
        if not (r and opt and t_opt):
            continue
        slope = _slope(rows, job, row, measure)
        out.append({"job": job, "row": row, "cpu": t["cpu"], "cpu_min": t["cpu_min"], "cpu_max": t["cpu_max"],
                    "runs": t["runs"], "depth": t["depth"], "time_ratio": t["cpu"] / t_opt["cpu"],
                    "ratio_equal_spp": r[measure] / opt[measure],
                    "ratio_equal_time": M.equal_time_ratio(r[measure], t["cpu"], opt[measure], t_opt["cpu"], slope)})
    return out


def _slope(rows, job, row, measure) -> float:
    pts = sorted((r["spp"], r[measure]) for r in rows if r["job"] == job and r["row"] == row and r[measure] > 0)
    if len(pts) < 2:
        return 1.0
    (n0, e0), (n1, e1) = pts[0], pts[-1]
    return max(0.5, min(2.0, -math.log(e1 / e0) / math.log(n1 / n0)))


def plot_errors(rows: Sequence[dict], jobs: Sequence[str], path: Path, measure: str = MAIN) -> None:
    """Error against spp, one panel per job, every sampler and the floor."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(jobs)
    if not n:
        return
    cols = min(4, n)
    fig, axes = plt.subplots((n + cols - 1) // cols, cols, figsize=(3.2 * cols, 2.6 * ((n + cols - 1) // cols)),
                             squeeze=False)
    order = [*G.SIMPLE, "start", "reference", *G.COLOUR_ROWS, G.PIXEL, "optimized", G.FLOOR,
             G.GENERIC_COLOURS]
    # One colour per row in every panel (a panel without a row must not shift the others').
    styles = {row: dict(color=f"C{i}") for i, row in enumerate(order)}
    styles["optimized"] = dict(color="k", lw=2)
    styles[G.FLOOR] = dict(color="0.5", ls=":", lw=2)
    spps = sorted({r["spp"] for r in rows if r["job"] in jobs})
    for ax, job in zip(axes.ravel(), jobs):
        for row in order:
            pts = sorted((r["spp"], r[measure]) for r in rows if r["job"] == job and r["row"] == row)
            if pts:
                ax.loglog(*zip(*pts), marker="o", ms=3, label=row, **styles[row])
        ax.set_title(job, fontsize=7)
        ax.set_xticks(spps, [str(n) for n in spps])
        ax.minorticks_off()
        ax.tick_params(labelsize=6)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    from matplotlib.lines import Line2D

    present = [row for row in order if any(r["row"] == row and r["job"] in jobs for r in rows)]
    axes[0, 0].legend([Line2D([], [], marker="o", ms=3, **styles[row]) for row in present], present, fontsize=5)
    fig.supxlabel("samples per pixel", fontsize=8)
    fig.supylabel(f"{measure} (seed pairs)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_lamp_heatmap(rows: Sequence[dict], jobs: Sequence[str], path: Path, spp: int, measure: str = MAIN) -> None:
    """Lamps x samplers: each sampler's error over the table's (log colour scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    cols = [*G.SIMPLE, "start"]
    data = []
    for j in jobs:
        opt = _table(rows, j, spp)
        data.append([(_get(rows, j, c, spp) or {measure: np.nan})[measure] / opt[measure] if opt else np.nan
                     for c in cols])
    data = np.array(data, dtype=float)
    if data.size == 0:
        return
    fig, ax = plt.subplots(figsize=(5.5, 0.17 * len(jobs) + 1.2))
    im = ax.imshow(data, aspect="auto", cmap="RdBu_r", norm=LogNorm(vmin=1 / 8, vmax=8))
    ax.set_xticks(range(len(cols)), cols, fontsize=7, rotation=30)
    ax.set_yticks(range(len(jobs)), [j.rsplit("/", 1)[0] for j in jobs], fontsize=5)
    for (i, k), v in np.ndenumerate(data):
        if np.isfinite(v):
            ax.text(k, i, f"{v:.2g}", ha="center", va="center", fontsize=4)
    fig.colorbar(im, ax=ax, label=f"{measure} / optimized table's, {spp} spp")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def plot_equal_time(et: Sequence[dict], path: Path) -> None:
    """Per timed job: each sampler's error ratio to the table at equal spp and at equal time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    jobs = sorted({e["job"] for e in et})
    if not jobs:
        return
    rows = [*G.SIMPLE, "start"]
    fig, ax = plt.subplots(figsize=(8, 3))
    w = 0.8 / len(rows)
    for i, row in enumerate(rows):
        vals = [next((e["ratio_equal_time"] for e in et if e["job"] == j and e["row"] == row), np.nan) for j in jobs]
        ax.bar(np.arange(len(jobs)) + i * w, vals, w, label=row)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(jobs)) + 0.4, [j.split("/")[0] for j in jobs], rotation=30, fontsize=7)
    ax.set_ylabel("error / table's at equal CPU time", fontsize=8)
    ax.legend(fontsize=6, ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def weight_wins(rows: Sequence[dict], spp: int, measure: str = MAIN) -> dict[str, int]:
    """How often each stratified weight (spd, luminance, xyz) has the least error of the three."""
    wins = {w: 0 for w in ("spd", "luminance", "xyz")}
    for j in jobs_of(rows):
        c = [(_get(rows, j, w, spp) or {measure: np.inf})[measure] for w in wins]
        if np.all(np.isfinite(c)):
            wins[list(wins)[int(np.argmin(c))]] += 1
    return wins


def _ratio(rows, job, a: str, b: str, spp: int, measure: str = MAIN) -> float:
    """Error of row ``a`` over row ``b`` on a job at spp (nan where either is missing)."""
    ra, rb = _get(rows, job, a, spp), _get(rows, job, b, spp)
    return ra[measure] / rb[measure] if ra and rb and rb[measure] > 0 else float("nan")


def _spread(values: Sequence[float], digits: int = 2) -> str:
    v = [x for x in values if math.isfinite(x)]
    if not v:
        return "–"
    d = digits
    return f"{np.median(v):.{d}f} ({min(v):.{d}f}-{max(v):.{d}f})" if len(v) > 1 else f"{v[0]:.{d}f}"


def regimes(rows: Sequence[dict]) -> list[tuple[str, list[str]]]:
    """The jobs grouped by regime: the lamp's kind (own-lamp scenes apart) and pixel sampler."""
    groups: dict[str, list[str]] = {}
    for j in jobs_of(rows):
        r = next(x for x in rows if x["job"] == j)
        groups.setdefault(f"{r['kind']}, {r['pixel_sampler']}", []).append(j)
    return sorted(groups.items())


def summary_table(rows: Sequence[dict], spp: int, measure: str = MAIN) -> str:
    """Markdown: per regime, median (range) over its jobs of the table's gain over the best
    simple sampler, over the ``spd`` table (emission sampling), over uniform and visible; the
    ``spd`` table's gain over pbrt-v4's visible sampling; the share of the removable error the
    table and the ``spd`` table remove; how often the table pays (``PAYS``)."""
    head = ("| regime | jobs | best simple / table | spd / table | uniform / table | visible / table | "
            "visible (pbrt-v4) / spd | table removes | spd removes | table pays |\n|" + "---|" * 10 + "\n")
    lines = []
    for name, js in regimes(rows):
        js = [j for j in js if _table(rows, j, spp)]
        if not js:
            continue
        g = [gain(rows, j, spp, measure) for j in js]
        opt = [_table(rows, j, spp)["row"] for j in js]
        spd_share = [100 * (_get(rows, j, "spd", spp) or {}).get("share_removed_de2", float("nan")) for j in js]
        pays = sum(1 for x in g if math.isfinite(x) and x >= PAYS)
        lines.append(f"| {name} | {len(js)} | {_spread(g)} | "
                     f"{_spread([_ratio(rows, j, 'spd', o, spp, measure) for j, o in zip(js, opt)])} | "
                     f"{_spread([_ratio(rows, j, 'uniform', o, spp, measure) for j, o in zip(js, opt)])} | "
                     f"{_spread([_ratio(rows, j, 'visible', o, spp, measure) for j, o in zip(js, opt)])} | "
                     f"{_spread([_ratio(rows, j, G.BUILTIN, 'spd', spp, measure) for j in js])} | "
                     f"{_spread([100 * _table(rows, j, spp)['share_removed_de2'] for j in js], 0)} % | "
                     f"{_spread(spd_share, 0)} % | {pays} of {len(js)} |")
    return head + "\n".join(lines) + "\n"


#: A job has something to gain when its best simple sampler is more than this factor above
#: the floor; the table "reaches the floor" there when its error above the floor is at most
#: ``FLOOR_SHARE`` of the best simple sampler's.
GAIN_ABOVE_FLOOR, FLOOR_SHARE = 1.1, 1.0 / 3.0


def floor_at(rows: Sequence[dict], job: str, spp: int, measure: str = MAIN) -> float:
    """The job's floor at ``spp``: rendered there, else the floor of the nearest lower spp
    scaled by spp_floor / spp (path noise falls as 1 / spp); nan without one."""
    have = sorted((r["spp"], r[measure]) for r in rows
                  if r["job"] == job and r["row"] == G.FLOOR and r["spp"] <= spp)
    if not have:
        return float("nan")
    n, e = have[-1]
    return e * n / spp


def above_floor_share(rows: Sequence[dict], job: str, row: str, spp: int, measure: str = MAIN) -> float:
    """(row's error - floor) / (best simple sampler's - floor); nan where the best simple
    sampler is within ``GAIN_ABOVE_FLOOR`` of the floor (nothing to gain) or a figure is missing."""
    r, fl = _get(rows, job, row, spp), floor_at(rows, job, spp, measure)
    if r is None or not math.isfinite(fl):
        return float("nan")
    best = best_simple(rows, job, spp, measure)[1]
    if not best > GAIN_ABOVE_FLOOR * fl:
        return float("nan")
    return (r[measure] - fl) / (best - fl)


def floor_table(rows: Sequence[dict], spp: int,
                tables: Sequence[str] = ("optimized", G.PIXEL, *G.COLOUR_ROWS, G.GENERIC_COLOURS, G.IMAGE),
                measure: str = MAIN) -> str:
    """Markdown: per regime, how many jobs have something to gain above the floor and in how
    many each table's error above the floor is at most ``FLOOR_SHARE`` of the best simple
    sampler's; median (range) of that share."""
    tables = [t for t in tables if any(r["row"] == t and r["spp"] == spp for r in rows)]
    head = ("| regime | jobs | nothing to gain | " + " | ".join(f"{t} reaches | {t}: share above floor" for t in tables)
            + " |\n|" + "---|" * (3 + 2 * len(tables)) + "\n")
    lines = []
    for name, js in regimes(rows):
        js = [j for j in js if _table(rows, j, spp) and math.isfinite(floor_at(rows, j, spp, measure))]
        if not js:
            continue
        cells = []
        nothing = sum(1 for j in js if not best_simple(rows, j, spp, measure)[1] > GAIN_ABOVE_FLOOR * floor_at(rows, j, spp, measure))
        for t in tables:
            sh = [x for x in (above_floor_share(rows, j, t, spp, measure) for j in js) if math.isfinite(x)]
            cells.append(f"{sum(x <= FLOOR_SHARE for x in sh)} of {len(sh)} | {_spread(sh) if sh else '–'}")
        lines.append(f"| {name} | {len(js)} | {nothing} | " + " | ".join(cells) + " |")
    return head + "\n".join(lines) + "\n"


def write_markdown(path: Path, rows: Sequence[dict], scores: Sequence[dict], et: Sequence[dict], spp: int,
                   command: str, images: Sequence[str]) -> None:
    """The report: checks, the ratio tables of both sweeps, equal time, the regime map."""
    L = [f"# Benchmark report\n\nWritten by `{command}`. Ratios are a sampler's error over the "
         f"optimized table's (above 1: the table is better) in `{MAIN}`, the mean squared CIEDE2000 of one "
         f"image from independent seed pairs, at {spp} spp unless a heading says otherwise.\n"]
    # Checks.
    zmax = {}
    for r in rows:
        zmax[r["row"]] = max(zmax.get(r["row"], 0.0), r["bias_z"] if math.isfinite(r["bias_z"]) else 99.0)
    n_img = len(rows) * 2
    L.append("## Checks\n\n- Unbiasedness: largest |z| of any image pair's mean against the reference's, per "
             f"sampler, over {len(jobs_of(rows))} jobs and every spp ({n_img} images; |z| above 4 would be a "
             "bias): " + ", ".join(f"{k} {v:.1f}" for k, v in sorted(zmax.items())) + ".")
    vis = [(r["mse"], _get(rows, r["job"], G.BUILTIN, r["spp"])) for r in rows if r["row"] == "visible"]
    ratios = [a / b["mse"] for a, b in vis if b and b["mse"] > 0]
    if ratios:
        L.append(f"- The `visible` table against pbrt-v4's own visible sampling: MSE ratio median "
                 f"{np.median(ratios):.3f} (range {min(ratios):.2f}-{max(ratios):.2f}) over {len(ratios)} "
                 "job-spp pairs; the two draw the same four quantiles in a different order of u.")
    tr = [(s["truth_de"], _get(rows, s["job"], "optimized", spp)) for s in scores]
    rel = [t / o["de"] for t, o in tr if o and o["de"] > 0]
    if rel:
        L.append(f"- The reference's own noise (mean CIEDE2000 of the reference itself, from its two halves) is "
                 f"{100 * np.median(rel):.0f} % of the optimized table's mean CIEDE2000 at {spp} spp in the "
                 f"median job (at most {100 * max(rel):.0f} %).")
    agree = [r["de2_ref"] / r["de2"] for r in rows if r["de2"] > 0 and r["row"] != G.FLOOR]
    if agree:
        L.append(f"- Squared CIEDE2000 against the reference with its noise subtracted over the seed-pair "
                 f"figure: median {np.median(agree):.3f}, 10-90 % {np.percentile(agree, 10):.2f}-"
                 f"{np.percentile(agree, 90):.2f} (1 when both measure the same thing).")
    wins = weight_wins(rows, spp)
    L.append(f"- Best stratified weight ({spp} spp, `{MAIN}`): " + ", ".join(f"{k} {v}" for k, v in wins.items())
             + " jobs.\n")
    for n in sorted({r["spp"] for r in rows}):
        L.append(f"## Summary by regime, {n} spp\n\nMedian (min-max) over the regime's jobs of `{MAIN}` ratios; "
                 f"\"table pays\": the table beats the best simple sampler by {PAYS}x or more.\n")
        L.append(summary_table(rows, n))
    for n in sorted({r["spp"] for r in rows}):
        table = floor_table(rows, n)
        if table.count("\n") > 2:
            L.append(f"## Against the floor, {n} spp\n\nPer regime: the jobs whose best simple sampler is "
                     f"within {GAIN_ABOVE_FLOOR}x of the floor (nothing to gain), and in how many of the others a "
                     f"table's `{MAIN}` above the floor is at most {FLOOR_SHARE:.2f} of the best simple sampler's "
                     "(the floor at a spp without one: the lower spp's, times its spp over this one); median "
                     "(range) of that share.\n")
            L.append(table)
    for sweep, title in (("scenes", "Scene sweep"), ("lamps", "Lamp sweep"), ("small", "Small grid")):
        for ps in ("sobol", "independent"):
            js = jobs_of(rows, sweep, ps)
            if not js:
                continue
            for n in sorted({r["spp"] for r in rows if r["job"] in js}):
                L.append(f"## {title}, {ps} pixel sampler, {n} spp\n")
                L.append(ratio_table(rows, js, n))
    if et:
        L.append("## Equal CPU time\n\nRender CPU seconds per image (one thread, "
                 f"{et[0].get('runs', '?')} runs alternating the samplers; median, min-max) and the error ratio to "
                 "the table at equal spp and at equal CPU time.\n")
        L.append("| job | sampler | CPU s | range | path depth | time / table's | ratio, equal spp | ratio, equal time |\n"
                 "|---|---|---|---|---|---|---|---|")
        for e in et:
            L.append(f"| {e['job']} | {e['row']} | {e['cpu']:.3f} | {e['cpu_min']:.3f}-{e['cpu_max']:.3f} | "
                     f"{e['depth']:.3f} | {e['time_ratio']:.3f} | {_fmt(e['ratio_equal_spp'])} | "
                     f"{_fmt(e['ratio_equal_time'])} |")
        L.append("")
    # Regime map.
    L.append(f"## Regime map ({spp} spp, `{MAIN}`)\n\nWhere the optimized table beats the best simple sampler "
             f"by {PAYS}x or more, and where it does not.\n")
    pays, not_pays = [], []
    for j in jobs_of(rows):
        g = gain(rows, j, spp)
        if math.isfinite(g):
            (pays if g >= PAYS else not_pays).append(f"{j} ({g:.2f}, best simple: {best_simple(rows, j, spp)[0]})")
    L.append(f"- **Pays ({len(pays)} jobs):** " + "; ".join(pays))
    L.append(f"- **Does not ({len(not_pays)} jobs):** " + "; ".join(not_pays) + "\n")
    for im in images:
        L.append(f"![{im}]({im})\n")
    Path(path).write_text("\n".join(L) + "\n")
