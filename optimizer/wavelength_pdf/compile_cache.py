"""The compile cache: where the optimizer keeps its compiled code between runs, how big it is,
and how to warm or clear it (design §7; ``wavelength-pdf cache info|clear|warm``).

The first ``optimize`` on a machine compiles the objective, its gradient and the report
functions for the table's grid size: :data:`FIRST_COMPILE` (measured: 45 s before the first
evaluation on a busy two-core machine). Later runs on a grid of the same size load the
compiled code in about a second (``objective.enable_compilation_cache``, ``aot``); another
spectrum on the same grid compiles nothing. A line lamp whose "auto" grid is refined to
another size compiles once more for that size.

The folder is ``$WAVELENGTH_PDF_JAX_CACHE`` (empty or ``off``: no cache), else
``$XDG_CACHE_HOME/wavelength-pdf/jax`` (``~/.cache/wavelength-pdf/jax``). It holds JAX's
persistent compilation cache (``jit_*-cache`` and ``*-atime`` files) and the package's own
executables (``executables/*.pkl`` and their key, ``executables/key``). :func:`clear` deletes
those files and nothing else, so a cache pointed at a folder that also holds other files
leaves them alone. This module imports no JAX unless it is asked whether the cache is warm.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path

#: The environment variable that moves (or, empty or ``off``, disables) the cache.
ENV = "WAVELENGTH_PDF_JAX_CACHE"
#: What the first compilation usually takes, as the progress line says it.
FIRST_COMPILE = "30-60 s on two cores"
#: The spectrum :func:`warm` compiles for by default (its "auto" grid is the default 5 nm one).
WARM_SPECTRUM = "cie:FL11"

_OFF = ("", "off", "0", "no")


def cache_dir() -> Path | None:
    """The cache folder the optimizer uses, or None when ``$WAVELENGTH_PDF_JAX_CACHE`` turns
    it off. The folder need not exist yet."""
    env = os.environ.get(ENV)
    if env is not None and env.strip().lower() in _OFF:
        return None
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "wavelength-pdf" / "jax"


def _is_ours(path: Path, top: bool) -> bool:
    """Whether ``path`` is a file the optimizer or JAX writes: JAX's cache entries in the
    folder itself; executables, their key and temporaries in ``executables/``."""
    name = path.name
    if top:
        return name.endswith(("-cache", "-atime")) and not name.startswith(".")
    return name.endswith(".pkl") or name == "key" or name.startswith(".tmp-")


def _files(folder: Path) -> list[Path]:
    """The cache's own regular files under ``folder`` (symbolic links are never followed)."""
    found = []
    for sub, top in ((folder, True), (folder / "executables", False)):
        try:
            entries = list(os.scandir(sub))
        except OSError:
            continue
        for e in entries:
            if e.is_file(follow_symlinks=False) and _is_ours(Path(e.path), top):
                found.append(Path(e.path))
    return found


@dataclass(frozen=True)
class CacheInfo:
    """What :func:`info` reports: the folder (None: the cache is off), whether it exists,
    how many of the cache's files it holds and their size in bytes, and whether it holds
    compiled code for this installation (same package sources, JAX, Python and CPU)."""

    path: Path | None
    exists: bool
    files: int
    bytes: int
    warm: bool

    def describe(self) -> str:
        if self.path is None:
            return (f"compile cache: off (${ENV} is empty or 'off'); every run compiles the "
                    f"optimizer, {FIRST_COMPILE}")
        state = ("holds compiled code for this installation" if self.warm else
                 "cold: the next optimize compiles first, " + FIRST_COMPILE)
        return (f"compile cache: {self.path}\n  {self.files} files, {_size(self.bytes)}; {state}\n"
                f"  move it with ${ENV}=DIR, turn it off with ${ENV}=off; "
                "'wavelength-pdf cache clear' empties it, 'wavelength-pdf cache warm' fills it")


def _size(n: int) -> str:
    for unit in ("bytes", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1000
    raise AssertionError


def is_warm(folder: Path | None = None) -> bool:
    """Whether ``folder`` (default: :func:`cache_dir`) holds an executable compiled for this
    installation: its file names carry :func:`wavelength_pdf.aot.environment_tag` (of the
    float64 mode the optimizer runs in).
    (A grid of a size not compiled before still compiles once.)"""
    folder = cache_dir() if folder is None else folder
    if folder is None:
        return False
    from wavelength_pdf import aot  # imports JAX

    tag = f"-{aot.environment_tag(x64=True)}-"
    return any(tag in p.name for p in _files(folder) if p.suffix == ".pkl")


def info(folder: Path | None = None, *, check_warm: bool = True) -> CacheInfo:
    """The cache's place and size (``folder`` default: :func:`cache_dir`)."""
    folder = cache_dir() if folder is None else folder
    if folder is None:
        return CacheInfo(None, False, 0, 0, False)
    files = _files(folder)
    size = 0
    for p in files:
        try:
            size += p.lstat().st_size
        except OSError:
            pass
    return CacheInfo(folder, folder.is_dir(), len(files), size,
                     check_warm and bool(files) and is_warm(folder))


def clear(folder: Path | None = None) -> tuple[int, int]:
    """Delete the cache's files (JAX's entries, the executables and their key) from ``folder``
    (default: :func:`cache_dir`); other files are left alone, and so are the folders. Returns
    (files deleted, bytes freed)."""
    folder = cache_dir() if folder is None else folder
    if folder is None:
        return 0, 0
    n = freed = 0
    for p in _files(folder):
        try:
            st = p.lstat()
            if not stat.S_ISREG(st.st_mode):
                continue
            p.unlink()
        except FileNotFoundError:
            continue
        n += 1
        freed += st.st_size
    return n, freed


def warm(spectra: list[str] | None = None, max_evals: int = 30) -> list[str]:
    """Compile what ``optimize`` needs for each spectrum's grid (default :data:`WARM_SPECTRUM`,
    whose "auto" grid is the default 5 nm one that most smooth spectra use) by running a short
    optimization whose table is thrown away. Returns one line per spectrum. (Measured: after
    ``warm``, a full default ``optimize cie:FL2`` took 10 s in all, against 45-65 s cold; it
    compiled one small function more.)"""
    import time

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
