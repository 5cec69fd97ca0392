"""The ``wavelength-pdf`` command: a thin layer over the package (SPEC 7).

Subcommands
-----------
optimize SPECTRUM -o TABLE
    Optimize the four wavelength densities for one spectrum (or one per distinct emitter of a
    pbrt-v4 scene) and write the table(s) with a comment header.
batch FOLDER -o OUTDIR
    Every spectrum file of a folder to a table each plus ``summary.csv``; parallel and
    resumable.
show TABLE
    Print a table's grid and normalization and, with ``--spectrum``, its objective and
    estimator health.

Bad input (a malformed or missing spectrum, scene or table) prints ``wavelength-pdf:
<file:line: reason>`` and exits with status 2; a result that fails the health checks is
not written and exits with status 1.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import warnings
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from wavelength_pdf import __version__
from wavelength_pdf.spectra import Spectrum, SpectrumError, load_spectra
from wavelength_pdf.produce import (field_of, format_value, make_grid, optimize_one, read_header, result_health,
                                    safe_name, summary_line)
from wavelength_pdf.table import TableError, read_table

PROG = "wavelength-pdf"

#: Exit status for bad input (a usage error, like argparse's).
EXIT_BAD_INPUT = 2
#: Exit status for a result that is not accepted (health checks failed).
EXIT_NOT_ACCEPTED = 1

#: File types ``batch`` picks up in a folder.
SPECTRUM_SUFFIXES = (".csv", ".spd", ".pbrt")

#: Columns of batch's summary.csv.
SUMMARY_FIELDS = [
    "input", "name", "table", "J_uniform", "J_init", "J", "J_fine", "J_over_uniform",
    "bias_rel", "std_rel_X", "std_rel_Y", "std_rel_Z", "accepted", "solver", "seconds",
    "status", "message",
]


class BadInput(Exception):
    """A command-line input problem that is not a spectrum or table error."""


# --------------------------------------------------------------------------------------
# Helpers shared by the subcommands
# --------------------------------------------------------------------------------------

def solver_names() -> list[str]:
    """Names in the solver registry (empty if the registry cannot be imported)."""
    try:
        from wavelength_pdf.solvers import SOLVERS
    except Exception:  # the registry is optional for --help; optimize reports the error
        return []
    return list(SOLVERS)


def output_paths(spectra: Sequence[Spectrum], out: str) -> list[Path]:
    """Where each spectrum's table goes.

    One spectrum: ``out`` itself (or ``out/<name>.csv`` if ``out`` is a directory). Several
    (a scene with several emitters): ``out`` is a directory (existing, or ending in '/') that
    gets ``<name>.csv`` each, or a pattern with ``{name}`` and/or ``{index}``.
    """
    if not out.strip():
        raise BadInput("-o: empty output path")
    pattern = "{name}" in out or "{index}" in out
    is_dir = Path(out).is_dir() or out.endswith(("/", os.sep))
    if len(spectra) == 1 and not pattern:
        return [Path(out) / f"{safe_name(spectra[0].name)}.csv" if is_dir else Path(out)]
    if pattern:
        paths = [Path(out.format(name=safe_name(s.name), index=i)) for i, s in enumerate(spectra)]
    elif is_dir:
        paths = [Path(out) / f"{safe_name(s.name)}.csv" for s in spectra]
    else:
        names = ", ".join(s.name for s in spectra)
        raise BadInput(f"{len(spectra)} emitter spectra ({names}) but -o {out} is one file: "
                       f"give a directory (ending in '/') or a pattern with {{name}} or {{index}}")
    if len(set(paths)) != len(paths):
        raise BadInput(f"-o {out} gives the same file to several spectra: use {{index}}")
    return paths


def _suffix_path(path: str | None, spectrum: Spectrum, several: bool) -> Path | None:
    """An image path, made distinct per spectrum when there are several."""
    if path is None:
        return None
    if "{name}" in path:
        return Path(path.replace("{name}", safe_name(spectrum.name)))
    p = Path(path)
    if not several:
        return p
    return p.with_name(f"{p.stem}-{safe_name(spectrum.name)}{p.suffix}")


class _Progress:
    """A tqdm progress bar on stderr that shows J falling (callback ``progress(step, J)``).

    The bar is drawn only when stderr is a terminal, at most a few times a second.
    """

    def __init__(self, name: str, enabled: bool, position: int | None = None):
        self.bar = None
        self.best = math.inf
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(desc=name[:30], unit="eval", file=sys.stderr, leave=False,
                            dynamic_ncols=True, position=position, mininterval=0.25,
                            disable=None)

    def __call__(self, step: int, J: float) -> None:
        if self.bar is None:
            return
        self.best = min(self.best, float(J))
        self.bar.set_postfix_str(f"J={self.best:.5g}", refresh=False)
        self.bar.update(max(0, int(step) - self.bar.n))

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# --------------------------------------------------------------------------------------
# optimize
# --------------------------------------------------------------------------------------

def cmd_optimize(args: argparse.Namespace) -> int:
    lo, hi = args.range
    grid = make_grid(lo, hi, args.grid_step)
    _check_solver(args.solver)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        spectra = load_spectra(args.spectrum, lo=lo, hi=hi)
    for w in caught:
        print(f"{PROG}: warning: {w.message}", file=sys.stderr)
    paths = output_paths(spectra, args.output)
    several = len(spectra) > 1
    status = 0
    for sp, path in zip(spectra, paths):
        bar = _Progress(sp.name, enabled=not args.quiet)
        try:
            out = optimize_one(sp, path, grid, args.solver, args.seed, args.max_seconds, bar,
                               _suffix_path(args.colour_bar, sp, several),
                               _suffix_path(args.plot, sp, several))
        finally:
            bar.close()
        print(summary_line(sp, out.result, path if out.written else None))
        if not out.written:
            h = result_health(out.result)
            reason = h.get("reason") or field_of(out.result, "message", "") or "health checks failed"
            print(f"{PROG}: {sp.name}: result not accepted ({reason}); table not written",
                  file=sys.stderr)
            status = EXIT_NOT_ACCEPTED
    return status


def _check_solver(name: str | None) -> None:
    if name is None:
        return
    names = solver_names()
    if names and name not in names:
        raise BadInput(f"unknown solver {name!r}; choose one of: {', '.join(names)}")


# --------------------------------------------------------------------------------------
# batch
# --------------------------------------------------------------------------------------

def _init_worker(threads: int | None) -> None:
    """Restrict a batch worker's XLA/BLAS threads (set before JAX starts its backend)."""
    if threads:
        os.environ["OMP_NUM_THREADS"] = str(threads)
        os.environ["OPENBLAS_NUM_THREADS"] = str(threads)
        flags = os.environ.get("XLA_FLAGS", "")
        if "intra_op_parallelism_threads" not in flags:
            os.environ["XLA_FLAGS"] = (flags + " --xla_cpu_multi_thread_eigen=false "
                                       f"intra_op_parallelism_threads={threads}").strip()


def _row(input_: str, name: str, table: str, status: str, message: str = "",
         values: dict | None = None) -> dict[str, Any]:
    row = {k: "" for k in SUMMARY_FIELDS}
    row.update(input=input_, name=name, table=table, status=status, message=message)
    row.update(values or {})
    return row


def _values_from_result(result: Any) -> dict[str, Any]:
    h = result_health(result)
    std = h.get("std_rel")
    ju, jr = field_of(result, "J_uniform"), field_of(result, "J")
    return {
        "J_uniform": format_value(ju), "J_init": format_value(field_of(result, "J_init")), "J": format_value(jr),
        "J_fine": format_value(field_of(result, "J_fine")),
        "J_over_uniform": format_value(float(jr) / float(ju)) if ju else "",
        "bias_rel": format_value(h.get("bias_rel")),
        "std_rel_X": format_value(std[0]) if std is not None else "",
        "std_rel_Y": format_value(std[1]) if std is not None else "",
        "std_rel_Z": format_value(std[2]) if std is not None else "",
        "accepted": bool(h.get("accepted")), "solver": str(field_of(result, "solver")),
        "seconds": format_value(field_of(result, "seconds")),
    }


def _values_from_header(header: dict[str, str]) -> dict[str, Any]:
    std = [v.strip() for v in header.get("std_rel", "").strip("[]").split(",") if v.strip()]
    std += [""] * (3 - len(std))
    return {
        "J_uniform": header.get("J_uniform", ""), "J_init": header.get("J_init", ""),
        "J": header.get("J", ""), "J_fine": header.get("J_fine", ""),
        "J_over_uniform": header.get("J_over_uniform", ""),
        "bias_rel": header.get("bias_rel", ""), "std_rel_X": std[0], "std_rel_Y": std[1],
        "std_rel_Z": std[2], "accepted": header.get("accepted", ""),
        "solver": header.get("solver", ""), "seconds": header.get("seconds", ""),
    }


def _batch_job(job: dict[str, Any]) -> dict[str, Any]:
    """One batch item, run in a worker process: optimize, write, return the summary row."""
    spec, out = job["spec"], Path(job["out"])
    try:
        lo, hi = job["range"]
        sp = load_spectra(spec, lo=lo, hi=hi)
        if len(sp) != 1:
            raise SpectrumError(f"{spec}: expected one spectrum, got {len(sp)}")
        o = optimize_one(sp[0], out, job["grid"] if isinstance(job["grid"], str) else np.asarray(job["grid"]), job["solver"], job["seed"],
                         job["max_seconds"], None)
        status = "written" if o.written else "not accepted"
        msg = "" if o.written else str(result_health(o.result).get("reason")
                                       or field_of(o.result, "message", ""))
        return _row(spec, sp[0].name, str(out) if o.written else "", status, msg,
                    _values_from_result(o.result))
    except (SpectrumError, TableError, BadInput, OSError, ValueError) as e:
        return _row(spec, "", "", "error", str(e))


def plan_batch(folder: Path, outdir: Path, lo: float, hi: float) -> tuple[list[tuple[str, Path, Path]], list[dict]]:
    """(spec, input file, table path) for every spectrum in ``folder``; rows for bad inputs.

    A scene with several emitter spectra gives one item per emitter (``scene.pbrt#i``), its
    tables named ``<stem>-<i>.csv``.
    """
    if not folder.is_dir():
        raise BadInput(f"{folder}: not a folder")
    items: list[tuple[str, Path, Path]] = []
    errors: list[dict] = []
    files = sorted(p for p in folder.iterdir()
                   if p.is_file() and p.suffix.lower() in SPECTRUM_SUFFIXES)
    for f in files:
        if f.suffix.lower() == ".pbrt":
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    n = len(load_spectra(str(f), lo=lo, hi=hi))
            except SpectrumError as e:
                errors.append(_row(str(f), "", "", "error", str(e)))
                continue
            if n == 1:
                items.append((str(f), f, outdir / f"{f.stem}.csv"))
            else:
                items += [(f"{f}#{i}", f, outdir / f"{f.stem}-{i}.csv") for i in range(n)]
        else:
            items.append((str(f), f, outdir / f"{f.stem}.csv"))
    return items, errors


def cmd_batch(args: argparse.Namespace) -> int:
    import concurrent.futures as cf
    import multiprocessing

    lo, hi = args.range
    grid = make_grid(lo, hi, args.grid_step)
    _check_solver(args.solver)
    folder, outdir = Path(args.folder), Path(args.output)
    items, rows = plan_batch(folder, outdir, lo, hi)
    if not items and not rows:
        raise BadInput(f"{folder}: no spectrum files ({', '.join(SPECTRUM_SUFFIXES)})")
    outdir.mkdir(parents=True, exist_ok=True)

    # Resume: a table newer than its input is kept (its header fills the summary).
    todo: list[dict[str, Any]] = []
    for spec, src, out in items:
        if not args.force and out.is_file() and out.stat().st_mtime >= src.stat().st_mtime:
            try:
                t = read_table(out)
                hdr = read_header(t)
                rows.append(_row(spec, hdr.get("name", ""), str(out), "kept",
                                 "table newer than input", _values_from_header(hdr)))
                continue
            except TableError:
                pass  # unreadable: redo it
        todo.append({"spec": spec, "out": str(out), "range": (lo, hi), "grid": grid if isinstance(grid, str) else grid.tolist(),
                     "solver": args.solver, "seed": args.seed, "max_seconds": args.max_seconds})

    jobs = max(1, args.jobs or 1)
    bar = None
    if not args.quiet and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc="batch", unit="spectrum", file=sys.stderr,
                   disable=None)
    try:
        if jobs == 1 or len(todo) <= 1:
            for job in todo:
                row = _batch_job(job)
                rows.append(row)
                _batch_report(row, bar, args.quiet)
        else:
            # JAX is not fork-safe: workers are spawned, each with one XLA thread.
            ctx = multiprocessing.get_context("spawn")
            with cf.ProcessPoolExecutor(max_workers=jobs, mp_context=ctx,
                                        initializer=_init_worker, initargs=(1,)) as pool:
                futures = [pool.submit(_batch_job, job) for job in todo]
                for fut in cf.as_completed(futures):
                    row = fut.result()
                    rows.append(row)
                    _batch_report(row, bar, args.quiet)
    finally:
        if bar is not None:
            bar.close()

    rows.sort(key=lambda r: r["input"])
    summary = outdir / "summary.csv"
    tmp = summary.with_name(f".{summary.name}.tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=SUMMARY_FIELDS)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, summary)
    bad = [r for r in rows if r["status"] not in ("written", "kept")]
    n_ok = len(rows) - len(bad)
    print(f"{n_ok}/{len(rows)} tables in {outdir} ({sum(r['status'] == 'kept' for r in rows)} "
          f"kept from an earlier run); summary: {summary}")
    if any(r["status"] == "error" for r in bad):
        return EXIT_BAD_INPUT
    return EXIT_NOT_ACCEPTED if bad else 0


def _batch_report(row: dict[str, Any], bar, quiet: bool) -> None:
    if row["status"] != "written":
        msg = f"{PROG}: {row['input']}: {row['status']}: {row['message']}"
        (bar.write(msg, file=sys.stderr) if bar is not None else print(msg, file=sys.stderr))
    elif not quiet:
        msg = (f"{row['name']}: J {row['J']} ({row['J_over_uniform']} x uniform), "
               f"{float(row['seconds'] or 0):.1f} s -> {row['table']}")
        (bar.write(msg, file=sys.stderr) if bar is not None else print(msg))
    if bar is not None:
        bar.update(1)


# --------------------------------------------------------------------------------------
# show
# --------------------------------------------------------------------------------------

def cmd_show(args: argparse.Namespace) -> int:
    table = read_table(args.table)
    grid, pdfs = table.grid, table.pdfs
    steps = np.diff(grid)
    uniform = np.allclose(steps, steps[0], rtol=1e-9, atol=0)
    print(f"table: {args.table}")
    for c in table.comments:
        print(f"  # {c}")
    print(f"grid: {grid.size} nodes, {grid[0]:g}-{grid[-1]:g} nm, "
          + (f"step {steps[0]:g} nm" if uniform else
             f"irregular steps {steps.min():g}-{steps.max():g} nm"))
    mass = np.sum(0.5 * (pdfs[:, 1:] + pdfs[:, :-1]) * steps, axis=1)
    for k in range(pdfs.shape[0]):
        nz = np.flatnonzero(pdfs[k] > 0)
        print(f"pdf{k}: integral {mass[k]:.15g}, max {pdfs[k].max():.6g} /nm at "
              f"{grid[int(np.argmax(pdfs[k]))]:g} nm, non-zero {grid[nz[0]]:g}-{grid[nz[-1]]:g} nm")
    mix = pdfs.mean(axis=0)
    zero = grid[mix <= 0]
    print(f"mixture: min {mix.min():.6g} /nm" +
          (f", ZERO at {zero.size} nodes ({zero[0]:g}-{zero[-1]:g} nm)" if zero.size else
           ", positive at every node"))
    if args.spectrum:
        lo, hi = float(grid[0]), float(grid[-1])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            spectra = load_spectra(args.spectrum, lo=lo, hi=hi)
        from wavelength_pdf.optimize import evaluate_table

        for sp in spectra:
            ev = evaluate_table(sp, table)
            h = result_health(ev)
            ju, j = field_of(ev, "J_uniform"), field_of(ev, "J")
            print(f"{sp.name}: J {float(j):.6g}" +
                  (f" (J_fine {float(field_of(ev, 'J_fine')):.6g})" if field_of(ev, "J_fine") is not None else "") +
                  (f", uniform {float(ju):.6g}, ratio {float(j) / float(ju):.4f}" if ju else ""))
            if h:
                std = h["std_rel"]
                print(f"  health: bias_rel {float(h['bias_rel']):.3g}, std/c "
                      f"{'/'.join(f'{v:.4g}' for v in std)}, "
                      f"{'accepted' if h['accepted'] else 'NOT accepted: ' + str(h['reason'])}")
    return 0


# --------------------------------------------------------------------------------------
# Parser
# --------------------------------------------------------------------------------------

_SPECTRUM_HELP = ("a spectrum: an LSPDD export (.csv), a pbrt .spd file, a pbrt-v4 scene "
                  "(.pbrt: one table per distinct emitter spectrum; scene.pbrt#N picks one), "
                  "cie:NAME (colour-science illuminant, e.g. cie:FL11) or lamp:NAME "
                  "(colour-science light source)")


class _Formatter(argparse.HelpFormatter):
    """argparse's formatter without breaking lines at hyphens (solver names stay whole)."""

    def _split_lines(self, text: str, width: int) -> list[str]:
        import textwrap

        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        import textwrap

        return textwrap.fill(" ".join(text.split()), width, initial_indent=indent,
                             subsequent_indent=indent, break_on_hyphens=False)


def _positive_seconds(text: str) -> float:
    """``--max-seconds``: a finite number of seconds > 0 (not 0, negative, nan or inf)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0, got {text!r}")
    return v


def _positive_int(text: str) -> int:
    """``--jobs``: an integer >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {text!r}")
    return v


def _range_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--range", nargs=2, type=float, metavar=("LO", "HI"),
                        default=(380.0, 780.0),
                        help="wavelength range of the table, nm (default: 380 780)")
    parser.add_argument("--grid-step", default="auto", metavar="NM",
                        help="spacing of the table's nodes, nm, which must divide the range; "
                             "or 'auto' (default): 5 nm over 380-780, refined around the lines "
                             "of a line lamp where that lowers J")


def _default_solver() -> str:
    try:
        from wavelength_pdf.solvers import DEFAULT_SOLVER
    except Exception:
        return "the package's default strategy"
    return str(DEFAULT_SOLVER)


def _solver_args(parser: argparse.ArgumentParser, names: list[str]) -> None:
    listing = ", ".join(names) if names else "see wavelength_pdf.solvers.SOLVERS"
    parser.add_argument("--solver", default=None, metavar="NAME",
                        help=f"solver from the registry: {listing} (default: "
                             f"{_default_solver()})")
    parser.add_argument("--seed", type=int, default=0, metavar="N",
                        help="random seed; same input and seed give the same table "
                             "(default: 0)")
    parser.add_argument("--max-seconds", type=_positive_seconds, default=None, metavar="S",
                        help="cap on the solver's wall time per spectrum, seconds; the "
                             "best table found so far is kept (default: the solver's own "
                             "evaluation budget, which keeps results reproducible)")
    parser.add_argument("--quiet", "-q", action="store_true",
                        help="no progress bar (the one-line summary is still printed)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``wavelength-pdf`` (optimize, batch, show, evaluate, grid, demo)."""
    names = solver_names()
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=_Formatter,
        description="Optimized wavelength-sampling densities for spectral rendering under "
                    "spiky lamps: four piecewise-linear densities whose balance-heuristic "
                    "colour estimate varies least in CIEDE2000 (see SPEC.md).",
        epilog="solvers: " + (", ".join(names) if names else "(registry unavailable)") +
               ". Bad input exits with status 2, a result failing the health checks with 1.",
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND",
                           title="commands (run 'wavelength-pdf COMMAND --help' for details)")

    o = sub.add_parser("optimize", formatter_class=_Formatter, help="optimize the wavelength table of a spectrum",
                       description="Optimize four wavelength densities for SPECTRUM and "
                                   "write them as a table (SPEC 2) with a comment header. "
                                   "A result that fails the health checks (bias, std worse "
                                   "than the initialization) is not written (exit 1).")
    o.add_argument("spectrum", metavar="SPECTRUM", help=_SPECTRUM_HELP)
    o.add_argument("-o", "--output", required=True, metavar="TABLE",
                   help="output table (.csv); for a scene with several emitters, a "
                        "directory (ending in '/') or a pattern with {name} or {index}")
    _solver_args(o, names)
    _range_arg(o)
    o.add_argument("--colour-bar", "--color-bar", dest="colour_bar", metavar="PNG",
                   help="also write a colour bar image: the estimated colour for every u "
                        "(rows: initialization, result, target)")
    o.add_argument("--plot", metavar="PNG",
                   help="also write a plot of the four densities over the spectrum")
    o.set_defaults(func=cmd_optimize)

    b = sub.add_parser("batch", formatter_class=_Formatter, help="optimize every spectrum file of a folder",
                       description="Optimize every spectrum file (.csv, .spd, .pbrt) in "
                                   "FOLDER to a table each in OUTDIR, plus OUTDIR/summary.csv. "
                                   "Resumable: a table newer than its input is kept.")
    b.add_argument("folder", metavar="FOLDER", help="folder of spectrum files")
    b.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="output folder for the tables and summary.csv")
    b.add_argument("--jobs", "-j", type=_positive_int, default=1, metavar="N",
                   help="parallel worker processes, one XLA thread each (default: 1)")
    b.add_argument("--force", action="store_true",
                   help="redo every spectrum, even where a newer table exists")
    _solver_args(b, names)
    _range_arg(b)
    b.set_defaults(func=cmd_batch)

    s = sub.add_parser("show", formatter_class=_Formatter, help="print a table's grid, normalization, J and health",
                       description="Print a table's grid, the normalization of its four "
                                   "densities and its header; with --spectrum, its "
                                   "objective J and estimator health for that spectrum.")
    s.add_argument("table", metavar="TABLE", help="table file (either layout of SPEC 2)")
    s.add_argument("--spectrum", metavar="SPECTRUM",
                   help="evaluate J and health of the table for this spectrum (" +
                        _SPECTRUM_HELP + ")")
    s.set_defaults(func=cmd_show)

    # The evaluation (SPEC 6): evaluate, grid and demo (the README's main job).
    from wavelength_pdf.evaluation.commands import add_subcommands

    add_subcommands(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``wavelength-pdf``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    try:
        return int(args.func(args) or 0)
    except (SpectrumError, TableError, BadInput, ValueError) as e:
        # ValueError: input the numerical core rejects (e.g. a spectrum with no luminance).
        print(f"{PROG}: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:  # missing file or folder, permission denied, disk full
        where = f"{e.filename}: " if e.filename else ""
        print(f"{PROG}: {where}{e.strerror or e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as e:  # the renderer failed, or an evaluation's table was not accepted
        print(f"{PROG}: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
