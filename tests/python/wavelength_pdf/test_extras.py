"""The optional parts: optimizing needs none of the evaluation's dependencies (Dask, OpenEXR,
matplotlib), and a command that needs one says which extra to install before it starts.

Each check runs ``wavelength-pdf`` in a fresh interpreter where those modules cannot be
imported (``sys.modules[name] = None`` makes every ``import name`` fail as if it were absent).
"""
from __future__ import annotations

import os
import subprocess
import sys
import tomllib

import pytest

from repo_paths import REPO
from wavelength_pdf import extras
from wavelength_pdf.table import read_table

ABSENT = ("matplotlib", "OpenEXR", "distributed", "dask")

PRELUDE = """
import sys
for name in {absent!r}:
    sys.modules[name] = None
from wavelength_pdf.cli import main
status = main(sys.argv[1:])
leaked = sorted(m for m in {absent!r} if sys.modules.get(m) is not None)
assert not leaked, leaked
sys.exit(status)
"""


def run_without_extras(*args: str, cwd=None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "python"), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-c", PRELUDE.format(absent=ABSENT), *args],
                          capture_output=True, text=True, timeout=600, env=env, cwd=cwd)


def test_the_extras_are_pyprojects():
    """extras.EXTRAS names the top-level module of every requirement of pyproject's extras."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    module_of = {"matplotlib": "matplotlib", "OpenEXR": "OpenEXR", "distributed": "distributed",
                 "mitsuba": "mitsuba", "cyipopt": "cyipopt"}
    for extra, modules in extras.EXTRAS.items():
        required = [r.split(">")[0].split("=")[0].split("<")[0].strip()
                    for r in project["optional-dependencies"][extra]]
        assert sorted(module_of[r] for r in required) == sorted(modules), extra
    core = " ".join(project["dependencies"])
    for name in ("matplotlib", "OpenEXR", "distributed", "dask"):
        assert name not in core, f"{name} is a dependency of the core package"


def test_optimize_needs_no_extra(tmp_path):
    out = tmp_path / "fl11.csv"
    r = run_without_extras("optimize", "cie:FL11", "-o", str(out), "--max-evals", "5", "--quiet")
    assert r.returncode in (0, 1), r.stderr  # 1: a result not accepted after 5 evaluations
    if r.returncode == 0:
        assert read_table(out).pdfs.shape[0] == 4
    table = out if out.is_file() else REPO / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
    r = run_without_extras("show", str(table), "--spectrum", "cie:FL11")
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("args, extra", [
    (["demo", "-o", "{tmp}/demo"], "evaluation"),
    (["evaluate", str(REPO / "scenes" / "cornell-box" / "scene.pbrt"), "cie:FL11", "-o", "{tmp}/e"],
     "evaluation"),
    (["benchmark", "-o", "{tmp}/b"], "evaluation"),
    (["optimize", "cie:FL11", "-o", "{tmp}/t.csv", "--plot", "{tmp}/t.png"], "plots"),
])
def test_a_command_of_an_extra_says_which_before_it_starts(tmp_path, args, extra):
    r = run_without_extras(*[a.format(tmp=tmp_path) for a in args])
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert f'.[{extra}]' in r.stderr and "matplotlib" in r.stderr, r.stderr
    assert r.stderr.count("\n") == 1, r.stderr  # one line, no traceback
    assert list(tmp_path.iterdir()) == [], "nothing written before the check"
