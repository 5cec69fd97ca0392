"""Input files for the readers' tests: the shared edge-case tables, and files that are not
regular files (a FIFO, a device that never ends) read in a fresh interpreter whose time and
memory are bounded, so that a reader that hangs or reads without end fails the test instead
of stopping the suite or the machine (design §2.3, §3.3).
"""
from __future__ import annotations

import csv
import os
import resource
import subprocess
import sys
from pathlib import Path

from repo_paths import REPO

#: The tables every table reader is tested on (tests/data/tables/edge/expected.csv).
EDGE_TABLES = REPO / "tests" / "data" / "tables" / "edge"


def edge_table_cases() -> list[tuple[str, int | None, int | None, str]]:
    """(file, nodes, line, reason) for each table of ``EDGE_TABLES``: ``nodes`` for a table
    that is accepted, ``line`` and ``reason`` for one that is refused."""
    with open(EDGE_TABLES / "expected.csv", newline="", encoding="utf-8") as fh:
        rows = csv.DictReader(line for line in fh if not line.startswith("#"))
        return [(r["file"], int(r["nodes"]) if r["nodes"] else None,
                 int(r["line"]) if r["line"] else None, r["reason"]) for r in rows]


def same_table_pairs() -> list[tuple[str, str]]:
    """(file, same_as) for each pair of ``EDGE_TABLES`` that must read as the same table
    (tests/data/tables/edge/same.csv)."""
    with open(EDGE_TABLES / "same.csv", newline="", encoding="utf-8") as fh:
        rows = csv.DictReader(line for line in fh if not line.startswith("#"))
        return [(r["file"], r["same_as"]) for r in rows]


_READ = """
import sys
from importlib import import_module
module, _, name = sys.argv[1].partition(":")
try:
    getattr(import_module(module), name)(sys.argv[2])
except Exception as e:
    print(type(e).__name__ + ": " + str(e))
    sys.exit(3)
print("read")
"""


def _limit_memory(nbytes: int):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (nbytes, nbytes))
    return apply


def read_bounded(reader: str, path: str | os.PathLike, seconds: float = 60,
                 memory: int = 2 << 30) -> tuple[int, str]:
    """Call ``reader`` ("module:function") on ``path`` in a fresh interpreter with at most
    ``memory`` bytes of address space; returns (exit status, output): 3 and
    "ErrorType: message" when it raised, 0 and "read" when it read the file. A reader still
    running after ``seconds`` is killed and reported as status -1."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO / "python"), os.environ.get("PYTHONPATH", "")]))
    try:
        r = subprocess.run([sys.executable, "-c", _READ, reader, str(path)], capture_output=True,
                           text=True, timeout=seconds, env=env, preexec_fn=_limit_memory(memory))
    except subprocess.TimeoutExpired:
        return -1, f"still reading {path} after {seconds:g} s"
    return r.returncode, (r.stdout + r.stderr).strip()


def make_fifo(folder: Path, name: str) -> Path:
    """A FIFO (named pipe) nobody writes to: opening it to read blocks for ever."""
    path = folder / name
    os.mkfifo(path)
    return path


def link_to_dev_zero(folder: Path, name: str) -> Path:
    """``name`` in ``folder``, a symbolic link to /dev/zero (endless zero bytes)."""
    path = folder / name
    path.symlink_to("/dev/zero")
    return path


def sphere_scene(resolution: int, spp: int) -> str:
    """A pbrt-v4 scene of one sphere under an infinite light, ``resolution`` pixels square at
    ``spp``: as slow to render (or, large, to write) as a test needs."""
    return (f'Film "rgb" "integer xresolution" [ {resolution} ] "integer yresolution" [ {resolution} ]\n'
            f'Sampler "independent" "integer pixelsamples" [ {spp} ]\n'
            'WorldBegin\nLightSource "infinite"\nShape "sphere"\n')
