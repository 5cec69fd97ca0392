"""Running the renderer for the evaluation: one image per (scene, sampler, spp, seed).

Each render is a subprocess of ``build/pbrt``; its wall-clock time (start-up and scene
loading included, the same for every sampler) is what the error-against-time plots use.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import re
import subprocess
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from wavelength_pdf.data import CHECKOUT
from wavelength_pdf.renderer import find_pbrt

REPO = CHECKOUT


class RenderError(RuntimeError):
    """The renderer failed; the message carries its stderr."""


@dataclass(frozen=True)
class Sampler:
    """A wavelength sampler of the comparison and the renderer options that select it."""

    name: str
    label: str
    args: tuple[str, ...]


def samplers(table: Path | None, lo: float, hi: float) -> dict[str, Sampler]:
    """The samplers of design §6: the baseline, pbrt-v4's default and the table."""
    out = {
        "uniform": Sampler("uniform", f"stratified uniform {lo:g}-{hi:g} nm",
                           ("--wavelength-sampling", "uniform", "--wavelength-range", f"{lo:g}", f"{hi:g}")),
        "visible": Sampler("visible", "pbrt-v4 visible", ("--wavelength-sampling", "visible")),
    }
    if table is not None:
        out["table"] = Sampler("table", "optimized table", ("--wavelength-pdf", str(table)))
    return out


@dataclass(frozen=True)
class Render:
    """A finished render: the image and how long it took."""

    image: Path
    seconds: float


def file_digest(*paths: Path, extra: str = "") -> str:
    """A short content hash of files and a string (cache keys)."""
    h = hashlib.sha256(extra.encode())
    for p in paths:
        h.update(_content_hash(Path(p)))
    return h.hexdigest()[:16]


#: Content hashes of large files (the renderer) are cached by (path, inode, size, times): a
#: grid asks for the renderer's hash once per render, and reading a binary of tens of MB ten
#: thousand times took longer than the renders. Small files (scenes, tables) are hashed every
#: time, since one rewritten within the file system's timestamp tick would keep a stale hash.
_CACHED_FROM = 1 << 20


def _content_hash(path: Path) -> bytes:
    st = path.stat()
    if st.st_size < _CACHED_FROM:
        return hashlib.sha256(path.read_bytes()).digest()
    return _large_file_hash(str(path.resolve()), st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)


@functools.lru_cache(maxsize=16)
def _large_file_hash(path: str, *identity: int) -> bytes:
    """The hash of a large file, cached by its path and ``identity`` (inode, size, times)."""
    return hashlib.sha256(Path(path).read_bytes()).digest()


def _run(cmd: list[str], on_percent: Callable[[int], None] | None) -> tuple[int, str]:
    """Run the renderer; returns its exit status and stderr (without progress-bar lines).

    With ``on_percent``, the renderer draws its progress bar ("... [+++   ]  37% ...") on
    stderr, which is read as it comes and reported as percentages."""
    if on_percent is None:
        proc = subprocess.run(cmd, capture_output=True, text=True)
        return proc.returncode, proc.stderr
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    kept, pending = [], b""
    assert proc.stderr is not None
    while chunk := proc.stderr.read1(4096):
        *lines, pending = re.split(rb"[\r\n]", pending + chunk)
        for line in lines:
            m = _PERCENT.search(line)
            if m:
                on_percent(int(m[1]))
            elif line.strip():
                kept.append(line.decode(errors="replace"))
    if pending.strip() and not _PERCENT.search(pending):
        kept.append(pending.decode(errors="replace"))
    return proc.wait(), "\n".join(kept)


#: The percentage in a line of the renderer's progress bar.
_PERCENT = re.compile(rb"\]\s+(\d+)%")


def cached(out: Path, key: str) -> Render | None:
    """The finished render at ``out`` if its JSON record carries ``key``, else None."""
    out = Path(out)
    meta = out.with_suffix(".json")
    if out.is_file() and meta.is_file():
        try:
            m = json.loads(meta.read_text())
        except ValueError:  # a record cut short (an old crash): render again
            return None
        if m.get("key") == key:
            return Render(out, float(m["seconds"]))
    return None


def render_key(scene: Path, sampler: Sampler, spp: int, seed: int, pbrt: Path | None = None) -> str:
    """The cache key of a render: the scene's, the binary's and the table's bytes, sampler, spp, seed."""
    pbrt = find_pbrt(pbrt)
    a = sampler.args
    tables = [Path(a[i + 1]) for i, x in enumerate(a[:-1]) if x == "--wavelength-pdf"]
    return file_digest(scene, pbrt, *tables, extra=json.dumps([sampler.args, spp, seed]))


def temporary(path: Path) -> Path:
    """A unique name beside ``path`` with its suffix (the renderer picks the format by it), for
    writing a file and then renaming it into place: a reader, or another worker doing the same
    render, never sees a partial file."""
    path = Path(path)
    return path.with_name(f".{path.stem}.{uuid.uuid4().hex[:12]}.tmp{path.suffix}")


def write_json(path: Path, record: dict) -> None:
    """Write a JSON record atomically (temporary file, then rename)."""
    tmp = temporary(path)
    tmp.write_text(json.dumps(record, indent=1))
    os.replace(tmp, path)


def render(scene: Path, out: Path, sampler: Sampler, spp: int, *, seed: int = 0,
           nthreads: int | None = None, pbrt: Path | None = None, cache: bool = True,
           on_percent: Callable[[int], None] | None = None) -> Render:
    """Render ``scene`` to ``out`` (EXR) unless an identical render is already there.

    A JSON file beside the image records the inputs' digest and the render time, so a rerun
    with the same scene, table, binary, sampler, spp and seed reuses it (resumable grids).
    Image and record are written under temporary names and renamed into place, so concurrent
    or repeated runs of the same render (a task retried after a worker died) are harmless.
    ``on_percent`` follows a long render's progress (0-100).
    """
    out = Path(out)
    pbrt = find_pbrt(pbrt)
    key = render_key(scene, sampler, spp, seed, pbrt)
    if cache and (done := cached(out, key)) is not None:
        return done
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary(out)
    cmd = [str(pbrt), *([] if on_percent else ["--quiet"]), "--spp", str(spp), "--seed", str(seed),
           *sampler.args, "--outfile", str(tmp)]
    if nthreads:
        cmd += ["--nthreads", str(nthreads)]
    cmd.append(str(scene))
    start = time.perf_counter()
    try:
        status, stderr = _run(cmd, on_percent)
        seconds = time.perf_counter() - start
        if status != 0 or not tmp.is_file():
            raise RenderError(f"{' '.join(cmd)} failed (exit {status}):\n{stderr.strip()}")
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    write_json(out.with_suffix(".json"), {"key": key, "seconds": seconds, "command": cmd,
                                          "nthreads": nthreads, "cpus": os.cpu_count()})
    return Render(out, seconds)
