"""Compiled objectives kept on disk as executables, so that a new process skips tracing
and lowering them.

JAX's persistent compilation cache (``compile_cache.enable_compilation_cache``) saves XLA's
compilation, but every process still traces each jitted function to a jaxpr, lowers it to
StableHLO and hashes the module to find it in the cache: for the objective, its gradient
and the report functions that is 2-3 s of CPU per process, a third of a short
``wavelength-pdf optimize`` run. :class:`DiskJit` wraps a jitted function and keeps, per
argument signature, the compiled executable itself (``jax.experimental.serialize_executable``)
in ``<cache>/executables``; a later process loads it and calls it directly.

The file name is the function's name, :func:`environment_tag` and a hash of the function's name, the argument signature (pytree structure,
shapes, dtypes, weak types, static arguments) and everything the compiled code depends on:
the package's source files, the JAX and jaxlib versions, Python's version, ``XLA_FLAGS``
and the CPU. The executable is the one a plain ``jax.jit`` call would run, so results are
the same with or without this cache. Anything that goes wrong (no cache directory, a file
that does not load or does not run, arguments being traced by an outer jit) falls back to
the plain jitted function; a file that does not load or run is deleted.

The files hold compiled machine code and a pickle, so a file planted in the folder would run
whatever it says. Two guards (design §7): the folder must belong to the user and be writable
by no one else (:func:`check_cache_folder`; otherwise no cache is used, with one warning,
and neither is JAX's own, which lives in the same folder), and each file carries an
HMAC-SHA256 of its name and content under a per-user secret key kept in the folder (``key``,
mode 0600, owned by the user): a file without a valid digest is never unpickled, only
deleted and compiled again.

A compilation cannot be cut short, so a time cap (``optimize --max-seconds``) is kept by not
starting one that would end past it: a call given a :class:`~wavelength_pdf.budget.Budget`
(``f(*args, budget=budget)``) that would have to compile raises :class:`CompileWouldOverrun`
when less time is left before the budget's deadline than the longest compilation of this
process took (``DEFAULT_COMPILE_SECONDS`` before the first).
"""

from __future__ import annotations

import hashlib
import hmac
import inspect
import os
import pickle
import platform
import secrets
import stat
import sys
import tempfile
import time
import weakref
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import jax

if TYPE_CHECKING:
    from .budget import Budget

_dir: Path | None = None
_env_keys: dict[bool, str] = {}  # environment_key() by float64 mode

#: What a compilation is expected to take before this process has timed one (seconds; the
#: search's objective with its gradient takes 2-5 s on one core).
DEFAULT_COMPILE_SECONDS = 3.0
_compile_seconds: list[float] = []  # the compilations of this process


class CompileWouldOverrun(RuntimeError):
    """A compilation would end past its budget's deadline."""


def _may_compile(name: str, budget: Budget | None) -> None:
    left = None if budget is None else budget.seconds_left()
    if left is None:
        return
    expected = max(_compile_seconds, default=DEFAULT_COMPILE_SECONDS)
    if left < expected:
        raise CompileWouldOverrun(f"compiling {name} takes about {expected:.1f} s; {max(left, 0.0):.1f} s "
                                  "of the time cap are left")


@contextmanager
def _timed_compilation():
    t = time.monotonic()
    yield
    _compile_seconds.append(time.monotonic() - t)


def check_cache_folder(path: str | os.PathLike) -> str:
    """Why the folder ``path`` may not hold compiled code, or '' when it may: it must be a
    directory owned by this user and writable by neither group nor others (anyone who can
    write there can make this process run their code)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError as e:
        return f"cannot open it ({e.strerror})"
    try:
        st = os.fstat(fd)
    finally:
        os.close(fd)
    if hasattr(os, "geteuid") and st.st_uid != os.geteuid():
        return f"it belongs to another user (uid {st.st_uid})"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"others may write in it (mode {stat.filemode(st.st_mode)})"
    return ""


def enable(path: str | os.PathLike | None) -> None:
    """Keep executables in ``path`` (None: do not keep them). A folder that
    :func:`check_cache_folder` refuses is not used."""
    global _dir, _key
    _key = None
    if path is None:
        _dir = None
        return
    p = Path(path)
    try:
        p.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError:
        _dir = None
        return
    _dir = None if check_cache_folder(p) else p


_key: bytes | None = None  # the secret of _dir, once read

#: The first bytes of every cache file, then the 32-byte HMAC, then the pickle.
_MAGIC = b"wavelength-pdf aot 1\n"


def _open_own(path: Path, flags: int) -> int:
    """A file descriptor of ``path``, refused (OSError) unless it is a regular file of this
    user that only this user may read or write; symbolic links are not followed."""
    fd = os.open(path, flags | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0))
    st = os.fstat(fd)
    if (not stat.S_ISREG(st.st_mode) or (hasattr(os, "geteuid") and st.st_uid != os.geteuid())
            or st.st_mode & 0o077):
        os.close(fd)
        raise OSError(f"{path}: not a private file of this user")
    return fd


def _secret() -> bytes | None:
    """The folder's secret key (32 random bytes in ``key``, created on first use), or None
    when there is no usable one (then nothing is read from or written to the folder)."""
    global _key
    if _key is not None or _dir is None:
        return _key
    path = _dir / "key"
    for _ in range(2):
        try:
            fd = _open_own(path, os.O_RDONLY)
            with os.fdopen(fd, "rb") as fh:
                data = fh.read(33)
            if len(data) == 32:
                _key = data
            return _key
        except FileNotFoundError:
            pass
        except OSError:
            return None
        try:  # first use: create it, private from the start (another process may race us)
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0),
                         0o600)
            with os.fdopen(fd, "wb") as fh:
                fh.write(secrets.token_bytes(32))
                fh.flush()
                os.fsync(fh.fileno())
        except FileExistsError:
            pass
        except OSError:
            return None
    return None


def _digest(key: bytes, name: str, payload: bytes) -> bytes:
    return hmac.new(key, name.encode() + b"\0" + payload, hashlib.sha256).digest()


def _sealed(name: str, payload: bytes) -> bytes | None:
    """The content of the cache file ``name`` for ``payload`` (None: no key)."""
    key = _secret()
    return None if key is None else _MAGIC + _digest(key, name, payload) + payload


def _unsealed(path: Path, name: str) -> bytes:
    """The payload of the cache file ``path`` written as ``name`` by this package; ValueError
    for a file whose digest is not valid (written by anyone else, or damaged)."""
    key = _secret()
    if key is None:
        raise ValueError("no key")
    with os.fdopen(_open_own(path, os.O_RDONLY), "rb") as fh:
        data = fh.read()
    mac, payload = data[len(_MAGIC):len(_MAGIC) + 32], data[len(_MAGIC) + 32:]
    if not (data.startswith(_MAGIC) and hmac.compare_digest(mac, _digest(key, name, payload))):
        raise ValueError(f"{path}: not written by this package")
    return payload


def _cpu_key() -> str:
    """What the host CPU supports (compiled code may use any of it)."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith(("flags", "Features")):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def environment_key(x64: bool | None = None) -> str:
    """Hash of everything besides the arguments that the compiled code depends on; ``x64``:
    for JAX's float64 mode on or off (default: as it is set now)."""
    if x64 is None:
        x64 = bool(jax.config.jax_enable_x64)
    if x64 not in _env_keys:
        import jaxlib

        h = hashlib.sha256()
        pkg = Path(__file__).resolve().parent
        for f in sorted(pkg.rglob("*.py")):
            h.update(f.relative_to(pkg).as_posix().encode())
            h.update(f.read_bytes())
        for part in (jax.__version__, getattr(jaxlib, "__version__", ""), sys.version,
                     platform.machine(), os.environ.get("XLA_FLAGS", ""), _cpu_key(),
                     str(x64)):
            h.update(b"\0" + str(part).encode())
        _env_keys[x64] = h.hexdigest()
    return _env_keys[x64]


def environment_tag(x64: bool | None = None) -> str:
    """The first 8 hex digits of :func:`environment_key`, written into every executable's file
    name, so that ``wavelength_pdf.compile_cache`` can tell whether the cache holds code for
    this installation without loading any (the optimizer runs with ``x64`` on)."""
    return environment_key(x64)[:8]


def _leaf_signature(x: Any):
    if isinstance(x, jax.core.Tracer):
        raise TypeError("traced")
    if hasattr(x, "shape") and hasattr(x, "dtype"):
        return (tuple(x.shape), str(x.dtype), bool(getattr(x, "weak_type", False)))
    if isinstance(x, (bool, int, float, complex)):
        return type(x).__name__
    raise TypeError(f"unsupported argument {type(x).__name__}")


#: Every :class:`DiskJit` of the process, for :func:`clear_memory`.
_instances: weakref.WeakSet = weakref.WeakSet()


def clear_memory() -> None:
    """Drop the executables the process holds in memory: every :class:`DiskJit`'s and JAX's
    own caches. A long process that compiles for many shapes (the benchmark's choices over a
    lamp sweep: each lamp's grid, each scene's pixels) otherwise keeps them all and runs out
    of memory maps (seen: LLVM "Cannot allocate memory" after 25 choices); later calls load
    them from disk again, or compile."""
    for f in list(_instances):
        f._compiled.clear()
    jax.clear_caches()


class DiskJit:
    """A jitted function whose executables are also kept on disk (see the module)."""

    def __init__(self, jitted: Callable, name: str, fn: Callable | None = None,
                 static_argnames: tuple[str, ...] = ()):
        self.jitted = jitted
        self.name = name
        self._compiled: dict = {}
        self._seen: set = set()  # signatures run without the disk cache
        self.__wrapped__ = jitted
        self._static = tuple(static_argnames)
        self._signature = inspect.signature(fn) if self._static else None
        _instances.add(self)

    def _split(self, args, static):
        """(non-static arguments, static ones as keywords, signature); the signature is
        None where it cannot be taken (arguments being traced by an outer jit)."""
        if self._static:
            # Static arguments given by position become keywords (they are part of the
            # signature, not arguments of the executable).
            bound = self._signature.bind(*args, **static)
            static = {k: v for k, v in bound.arguments.items() if k in self._static}
            args = tuple(v for k, v in bound.arguments.items() if k not in self._static)
        try:
            leaves, tree = jax.tree_util.tree_flatten(args)
            sig = (str(tree), tuple(_leaf_signature(x) for x in leaves), tuple(sorted(static.items())))
        except TypeError:
            sig = None
        return args, static, sig

    def __call__(self, *args, budget: Budget | None = None, **static):
        """``jitted(*args, **static)``; a call that has to compile first does so only if
        ``budget`` leaves time for it (:class:`CompileWouldOverrun` otherwise)."""
        if _dir is None:
            return self._plain(args, static, budget)
        args, static, sig = self._split(args, static)
        if sig is None:
            return self.jitted(*args, **static)
        fn = self._compiled.get(sig)
        if fn is None:
            fn = self._load_or_compile(sig, args, static, budget)
            self._compiled[sig] = fn
        return fn(*args)

    def bind(self, *args, budget: Budget | None = None, **static) -> Callable:
        """The executable for the signature of ``args`` (and these static arguments), to be
        called with the non-static arguments alone, positionally, on arguments of that same
        signature: a hot loop's calls then skip the signature check of every call (a pytree
        flatten and a string, a tenth of a millisecond on the solvers' objective). Loads or
        compiles it now, within ``budget`` like any first call."""
        self(*args, budget=budget, **static)
        args, static, sig = self._split(args, static)
        if _dir is None or sig is None:
            return partial(self.jitted, **static)
        return self._compiled[sig]

    def _plain(self, args, static, budget):
        """The jitted function; its first call per signature compiles, within ``budget``."""
        args, static, sig = self._split(args, static)
        if sig is None or sig in self._seen:
            return self.jitted(*args, **static)
        _may_compile(self.name, budget)
        with _timed_compilation():
            out = jax.block_until_ready(self.jitted(*args, **static))
        self._seen.add(sig)
        return out

    def _path(self, sig) -> Path:
        env = environment_key()
        key = hashlib.sha256(repr((self.name, sig, env)).encode()).hexdigest()[:40]
        return _dir / f"{self.name}-{env[:8]}-{key}.pkl"

    def _load(self, path: Path, args, name: str | None = None):
        from jax.experimental import serialize_executable

        # Unpickled only once its digest shows this package wrote it (the module's docstring).
        blob, in_tree, out_tree = pickle.loads(_unsealed(path, name or path.name))
        compiled = serialize_executable.deserialize_and_load(blob, in_tree, out_tree)
        jax.block_until_ready(compiled(*args))  # fails here, not later, if it cannot run
        return compiled

    def _load_or_compile(self, sig, args, static, budget):
        path = self._path(sig)
        if path.is_file():
            try:
                return self._load(path, args)
            except Exception:  # any unreadable or unrunnable file: recompile
                path.unlink(missing_ok=True)
        _may_compile(self.name, budget)
        with _timed_compilation():
            compiled = _compile_fresh(self.jitted.lower(*args, **static))
        try:
            from jax.experimental import serialize_executable

            data = _sealed(path.name, pickle.dumps(serialize_executable.serialize(compiled)))
            if data is None:
                return compiled
            fd, tmp = tempfile.mkstemp(dir=_dir, prefix=".tmp-")
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            try:
                self._load(Path(tmp), args, path.name)  # keep only what loads and runs
                os.replace(tmp, path)
            finally:
                Path(tmp).unlink(missing_ok=True)
        except Exception:  # not serializable here: this process uses it all the same
            pass
        return compiled


def _compile_fresh(lowered):
    """Compile without JAX's persistent cache: an executable JAX loaded from its cache
    serializes into one that does not run (XLA:CPU, jax 0.10: "Function ... not found")."""
    try:
        from jax.experimental.compilation_cache import compilation_cache as cc

        was = bool(jax.config.jax_enable_compilation_cache)
    except Exception:
        return lowered.compile()
    try:
        jax.config.update("jax_enable_compilation_cache", False)
        cc.reset_cache()
        return lowered.compile()
    finally:
        jax.config.update("jax_enable_compilation_cache", was)
        cc.reset_cache()


def disk_jit(fn: Callable, **jit_kwargs) -> DiskJit:
    """``jax.jit(fn, **jit_kwargs)`` with executables kept on disk (a decorator)."""
    return DiskJit(jax.jit(fn, **jit_kwargs), fn.__name__.lstrip("_"), fn,
                   tuple(jit_kwargs.get("static_argnames", ())))
