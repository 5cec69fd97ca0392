"""``wavelength-pdf cache info|clear|warm``: the optimizer's compile cache (design §7,
:mod:`wavelength_pdf.compile_cache`)."""
from __future__ import annotations

import argparse

from wavelength_pdf.cli import Formatter, positive_int


def help_text() -> str:
    """One paragraph for ``--help``: where the cache is, how big it is now, and the commands."""
    from wavelength_pdf import compile_cache as cc

    try:
        now = cc.info(check_warm=False)
    except OSError:
        now = None
    if now is not None and now.path is None:
        where = f"The compile cache is off (${cc.ENV} is empty or 'off'): every run compiles"
    else:
        size = f", {now.files} files, {cc._size(now.bytes)} now" if now is not None and now.exists else ", empty now"
        where = f"The compile cache: {now.path if now is not None else cc.cache_dir()}{size}"
    return (f"The first optimize compiles the optimizer for the table's grid size ({cc.FIRST_COMPILE}; "
            f"the progress line says so) and keeps the compiled code for later runs, which load it "
            f"in about a second. {where} (${cc.ENV}=DIR moves it, =off turns it off; it grows by a few "
            "MB per grid size and per package version, e.g. 100-300 MB after many versions). "
            "'wavelength-pdf cache info' shows it, 'cache clear' empties it, 'cache warm' compiles "
            "ahead of time.")


def warm(spectra: list[str] | None = None, max_evals: int = 30) -> list[str]:
    """Compile what ``optimize`` needs for each spectrum's grid (default
    ``compile_cache.WARM_SPECTRUM``, whose "auto" grid is the default 5 nm one that most smooth spectra use) by running a short
    optimization whose table is thrown away. Returns one line per spectrum. (Measured: after
    ``warm``, a full default ``optimize cie:FL2`` took 10 s in all, against 45-65 s cold; it
    compiled one small function more.)"""
    import time

    from wavelength_pdf.compile_cache import WARM_SPECTRUM
    from wavelength_pdf.optimize import optimize_spectrum
    from wavelength_pdf.spectra import load_spectrum

    lines = []
    for spec in spectra or [WARM_SPECTRUM]:
        t = time.monotonic()
        sp = load_spectrum(spec)
        result = optimize_spectrum(sp, solver_options={"max_evals": int(max_evals)})
        del result
        lines.append(f"{spec}: compiled or loaded in {time.monotonic() - t:.0f} s")
    return lines


def cmd_cache(args: argparse.Namespace) -> int:
    from wavelength_pdf import compile_cache as cc

    action = args.action or "info"
    if action == "info":
        print(cc.info().describe())
    elif action == "clear":
        folder = cc.cache_dir()
        if folder is None:
            print(f"compile cache: off (${cc.ENV}); nothing to clear")
            return 0
        n, freed = cc.clear(folder)
        print(f"compile cache: {folder}: deleted {n} files, {cc._size(freed)}")
    else:  # warm
        for line in warm(args.spectra or None, max_evals=args.max_evals):
            print(line)
        print(cc.info().describe())
    return 0


def add_parser(sub) -> None:
    from wavelength_pdf import compile_cache as cc

    c = sub.add_parser("cache", formatter_class=Formatter,
                       help="the optimizer's compile cache: where it is, its size; clear or warm it",
                       description=help_text())
    c.add_argument("action", nargs="?", choices=("info", "clear", "warm"), default="info",
                   help="info (default): the cache's folder, file count, size and whether it holds "
                        "code for this installation; clear: delete the cache's files (JAX's "
                        "entries and the executables with their key; nothing else in the folder); "
                        "warm: compile for SPECTRUM's grid by a short optimization whose table is "
                        "thrown away")
    c.add_argument("spectra", nargs="*", metavar="SPECTRUM",
                   help=f"with warm: spectra whose grids to compile for (default {cc.WARM_SPECTRUM}, "
                        "whose 'auto' grid is the default 5 nm one most smooth spectra use; a line "
                        "lamp's refined grid has a size of its own)")
    c.add_argument("--max-evals", type=positive_int, default=30, metavar="N",
                   help="with warm: evaluations of each short optimization (default 30)")
    c.set_defaults(func=cmd_cache)
