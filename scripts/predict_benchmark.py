#!/usr/bin/env python3
"""Does the objective predict the image? Predicted against measured error ratios over the
benchmark's jobs (docs/benchmark.md, "Does the objective predict the image?").

Reads a finished benchmark's results.csv and the tables its rows rendered with (OUT/tables,
OUT/jobs/.../optimized-scene.csv, SHARED/tables/reference-4x81), computes every prediction of
wavelength_pdf.predict for each row under the job's lamp, and writes prediction.csv (one line
per job, spp and compared row: measured and predicted ratio to the optimized table),
prediction-summary.csv (Spearman and spread), prediction.png and choice.csv (per job and
spp, the table or simple sampler that the last prediction ranks first, and its measured
error beside the table's and the best simple sampler's) into --docs.

    PYTHONPATH=optimizer python scripts/predict_benchmark.py -o /path/to/out/benchmark
"""
from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python"))


def main(argv=None) -> int:
    from wavelength_pdf.evaluation.benchmark import grid as G
    from wavelength_pdf.evaluation.benchmark import predict as BP

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("-o", "--outdir", type=Path, default=HERE.parent / "out" / "benchmark",
                    help="the benchmark's output folder, with tables/ and jobs/ (default out/benchmark)")
    ap.add_argument("--results", type=Path, default=None,
                    help="its results.csv (default OUTDIR/results.csv, else docs/benchmark/results.csv)")
    ap.add_argument("--shared", type=Path, default=G.SHARED, help=f"the shared material (default {G.SHARED})")
    ap.add_argument("--docs", type=Path, default=HERE.parent / "docs" / "benchmark",
                    help="where prediction.csv, prediction-summary.csv and prediction.png go (default docs/benchmark)")
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 64], help="sample counts (default 16 64)")
    ap.add_argument("--candidates", nargs="+", default=list(BP.CANDIDATES), choices=BP.CANDIDATES,
                    help="predictions to evaluate (default all; +floor variants follow their base)")
    ap.add_argument("--colours", choices=BP.COLOURS, default="white",
                    help="what the lamp lights in the predictions: a white surface (default); on the "
                         "ColorChecker jobs its 24 patches (colorchecker); or every job's own scene "
                         "colours, as the renderer builds them (scene; white where a scene has none); or "
                         "every lit pixel's own spectrum, from one render of each scene under a flat lamp "
                         "(pixels: covariance and covariance-lab only; +floor adds the measured floor "
                         "unscaled, the prediction being in the image's units)")
    ap.add_argument("--pbrt", type=Path, default=None,
                    help="with --colours scene or pixels: the renderer (default: as design §7)")
    ap.add_argument("--spread", action="store_true",
                    help="with --colours pixels: each pixel's spread (the spectra its samples see, from two "
                         "renders of an 8x finer copy, the same paths at independent wavelengths) in place of its incoherence (wavelength_pdf.evaluation."
                         "transfer.spread)")
    ap.add_argument("--net", action="store_true",
                    help="with --spread: the benchmark was rendered with --wavelength-net, which stratifies the "
                         "spread between a pixel's cells (design §6.8)")
    ap.add_argument("--only", nargs="+", default=None, metavar="PREFIX", help="only jobs whose name starts so")
    ap.add_argument("--pool", type=Path, nargs="+", default=None, metavar="CSV",
                    help="render and predict nothing: print the Spearman table over the pairs of these "
                         "prediction.csv files pooled (the candidates they all have) and exit")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)

    say = (lambda m: None) if a.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    if a.pool:
        return pool(a.pool)
    results = a.results or (a.outdir / "results.csv")
    if a.results is None and not results.is_file():
        results = HERE.parent / "docs" / "benchmark" / "results.csv"
    problems = []
    if a.spread and a.colours != "pixels":
        problems.append("--spread needs --colours pixels (it is a property of each pixel)")
    if a.net and not a.spread:
        problems.append("--net models the spread's cells: it needs --spread")
    if not results.is_file():
        problems.append(f"no results file {results}")
    if not (a.outdir / "tables").is_dir():
        problems.append(f"no benchmark tables under {a.outdir / 'tables'} (run `wavelength-pdf benchmark` "
                        "or pass -o the folder it wrote)")
    if not a.shared.is_dir():
        problems.append(f"no shared material at {a.shared} (the LSPDD lamps and earlier tables; --shared)")
    if problems:
        for p in problems:
            print(f"predict_benchmark: {p}", file=sys.stderr)
        return 2
    rows = BP.read_results(results)
    if a.only:
        rows = [r for r in rows if any(r["job"].startswith(o) for o in a.only)]
    jobs, missing = BP.plan(rows, a.outdir, a.shared)
    if missing:
        print(f"predict_benchmark: {len(missing)} inputs are missing:", file=sys.stderr)
        for m in missing[:20]:
            print(f"  {m}", file=sys.stderr)
        return 2
    if not jobs:
        print("predict_benchmark: no job selected", file=sys.stderr)
        return 2
    t0 = time.time()
    if a.colours == "pixels":
        a.candidates = [c for c in a.candidates if c in BP.PIXEL_CANDIDATES]
        own = [j.job for j in jobs if j.lamp == "own"]
        if own:
            say(f"predict_benchmark: --colours pixels leaves out {len(own)} jobs lit by their own lamps "
                f"(several kinds: not one lamp times the scene's transfer): {', '.join(own)}")
            jobs = [j for j in jobs if j.lamp != "own"]
    recs = BP.predict_jobs(rows, jobs, a.spp, a.candidates, a.colours, say, out=a.outdir, pbrt=a.pbrt,
                           spread=a.spread, net=a.net)
    BP.add_floor(recs, [f.split("+")[0] for f in BP.FLOORED if f.split("+")[0] in a.candidates],
                 fit=a.colours != "pixels")
    cands = [*a.candidates, *(f for f in BP.FLOORED if f.split("+")[0] in a.candidates)]
    if a.colours == "pixels":  # the floor predicted from the pixels too: nothing measured
        cands += [f"{c}+path" for c in a.candidates if f"{c}+path" in recs[0]]
    prs = BP.pairs(recs, cands)
    summ = BP.summary(prs, cands)
    a.docs.mkdir(parents=True, exist_ok=True)
    BP.write_csv(a.docs / "prediction.csv", prs, cands)
    with open(a.docs / "prediction-summary.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(summ[0]) if summ else ["candidate"])
        w.writeheader()
        for s in summ:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in s.items()})
    BP.plot(a.docs / "prediction.png", prs, cands)
    print(BP.markdown(summ))
    # The image's health rule: per job, the table or the simple sampler the best prediction
    # ranks first (with the measured floor where there is one: it does not change the order).
    chooser = "covariance+floor" if "covariance+floor" in cands else cands[-1]
    ch = BP.choices(recs, chooser)
    if ch:
        with open(a.docs / "choice.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(ch[0]))
            w.writeheader()
            for c in ch:
                w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in c.items()})
        print(f"\nChosen by {chooser}:\n")
        print(BP.choices_markdown(ch))
    say(f"predict_benchmark: {len(jobs)} jobs, {len(prs)} pairs in {time.time() - t0:.0f} s; "
        f"wrote {a.docs / 'prediction.csv'}, prediction-summary.csv, prediction.png")
    return 0


def pool(paths) -> int:
    """Spearman over several prediction.csv files' pairs together (e.g. two sweeps)."""
    from wavelength_pdf.evaluation.benchmark import predict as BP

    prs, cands = [], None
    for path in paths:
        try:
            more, cs = BP.read_pairs(path)
        except (OSError, ValueError) as e:
            print(f"predict_benchmark: {e}", file=sys.stderr)
            return 2
        prs += more
        cands = cs if cands is None else [c for c in cands if c in cs]
    if not cands:
        print("predict_benchmark: the files have no prediction in common", file=sys.stderr)
        return 2
    print(BP.markdown([s for s in BP.summary(prs, cands) if s["regime"] == "all"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
