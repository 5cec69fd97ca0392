"""The compile cache: where the optimizer keeps its compiled code between runs, how big it is,
and how to warm or clear it (design §7; ``wavelength-pdf cache info|clear|warm``).

The first ``optimize`` on a machine compiles the objective, its gradient and the report
functions for the table's grid size: :data:`FIRST_COMPILE` (measured: 45 s before the first
evaluation on a busy two-core machine). Later runs on a grid of the same size load the
compiled code in about a second (:func:`enable_compilation_cache`, ``aot``); another
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
import warnings
from dataclasses import dataclass
from pathlib import Path

#: The environment variable that moves (or, empty or ``off``, disables) the cache.
ENV = "WAVELENGTH_PDF_JAX_CACHE"
#: What the first compilation usually takes, as the progress line says it.
FIRST_COMPILE = "30-60 s on two cores"
#: The spectrum ``cache warm`` compiles for by default (its "auto" grid is the default 5 nm one).
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


_cache_dir: str | None = None


def enable_compilation_cache() -> str | None:
    """Keep compiled objectives on disk between runs (JAX's persistent compilation cache).

    Compiling the objective and its gradient takes 5-10 s per problem size; with the
    cache a later run (another spectrum, another process) loads them in about a second
    (this module: its place, size and ``clear``; ``cache warm`` fills it).
    The objective's functions are also kept as whole executables (``aot``), which skips
    tracing and lowering them in a later process.
    The directory is ``$WAVELENGTH_PDF_JAX_CACHE`` if set (empty or ``off`` disables the
    cache), else ``$XDG_CACHE_HOME/wavelength-pdf/jax`` (``~/.cache/...``). The cache only
    holds compiled code: results do not depend on it. Returns the directory, or None.

    Compiled code from the folder runs in this process, so a folder that another user owns
    or that group or others may write to is not used (one warning, no cache; design §7); the
    executables kept by ``aot`` also carry a digest under the user's own key.
    """
    global _cache_dir
    if _cache_dir is not None:
        return _cache_dir or None
    import jax

    from wavelength_pdf import aot

    path = cache_dir()  # design §7: the folder, or None when turned off
    if path is None:
        _cache_dir = ""
        return None
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        unsafe = aot.check_cache_folder(path)
        if unsafe:
            warnings.warn(f"not using the compile cache {path}: {unsafe}; compiled code there "
                          "could have been written by someone else (make it yours with "
                          "chmod 700, or set WAVELENGTH_PDF_JAX_CACHE to another folder)",
                          RuntimeWarning, stacklevel=2)
            _cache_dir = ""
            aot.enable(None)
            return None
        jax.config.update("jax_compilation_cache_dir", str(path))
        aot.enable(path / "executables")
        # Every compiled function, however quick to compile: a process compiles ~30.
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    except (OSError, AttributeError, ValueError):
        _cache_dir = ""
        return None
    _cache_dir = str(path)
    return _cache_dir
