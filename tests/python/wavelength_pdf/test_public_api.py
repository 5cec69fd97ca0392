"""The public API (the names in ``__all__``, CHANGELOG.md): what ``wavelength_pdf`` exports is typed for a type
checker (mypy sees the real signatures, not ``Any``), documented by ``help()``, and versioned
as CHANGELOG.md says."""
from __future__ import annotations

import os
import pydoc
import re
import subprocess
import sys
import tomllib

import pytest

import wavelength_pdf
from repo_paths import REPO

#: A user's script, with one mistake on its last line.
SNIPPET = '''\
import wavelength_pdf
from wavelength_pdf import (Result, Spectrum, Table, TableError, evaluate_table, evaluation_budget,
                            load_spectra, load_spectrum, optimize_spectrum, read_table, write_table)

sp = load_spectrum("cie:FL11")
reveal_type(sp)
reveal_type(load_spectra("cie:FL11"))
result = optimize_spectrum(sp, grid="auto", seed=1)
reveal_type(result)
reveal_type(result.accepted)
reveal_type(result.to_table())
reveal_type(read_table("t.csv"))
reveal_type(evaluate_table(sp, read_table("t.csv")))
reveal_type(evaluation_budget())
reveal_type(wavelength_pdf.__version__)
optimize_spectrum("cie:FL11")
'''
WANT = ["wavelength_pdf.spectra.Spectrum", "list[wavelength_pdf.spectra.Spectrum]", "wavelength_pdf.result.Result",
        "bool", "wavelength_pdf.table.Table", "wavelength_pdf.table.Table", "wavelength_pdf.result.Result", "int",
        "str"]
#: Third-party packages mypy need not read for the check (it would take minutes for JAX).
SKIP = ("jax.*,jaxlib.*,scipy.*,colour.*,matplotlib.*,distributed.*,dask.*,tqdm.*,OpenEXR.*,cyipopt.*,"
        "mitsuba.*,drjit.*,threadpoolctl.*,ml_dtypes.*")


def test_mypy_sees_the_typed_api(tmp_path):
    pytest.importorskip("mypy", reason="mypy is in the test extras (pip install '.[test]')")
    (tmp_path / "user.py").write_text(SNIPPET)
    (tmp_path / "mypy.ini").write_text(f"[mypy]\nfollow_imports = silent\nignore_missing_imports = True\n"
                                       f"cache_dir = {tmp_path / 'cache'}\n[mypy-{SKIP}]\nfollow_imports = skip\n")
    env = {**os.environ, "MYPYPATH": str(REPO / "python")}  # this checkout's package
    run = subprocess.run([sys.executable, "-m", "mypy", "--config-file", "mypy.ini", "user.py"], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=600)
    revealed = re.findall(r'Revealed type is "(.*)"', run.stdout)
    assert revealed == WANT, run.stdout + run.stderr
    errors = [line for line in run.stdout.splitlines() if ": error:" in line]
    assert len(errors) == 1 and "user.py:16:" in errors[0] and 'expected "Spectrum"' in errors[0], run.stdout


def test_the_type_checkers_names_are_the_run_time_api():
    """The TYPE_CHECKING imports of __init__.py and its lazy table name the same objects."""
    text = (REPO / "python" / "wavelength_pdf" / "__init__.py").read_text()
    block = text.split("if TYPE_CHECKING:")[1].split("\n\n")[0]
    typed = {}
    for module, names in re.findall(r"from (wavelength_pdf\.\w+) import ([\w, ]+)", block):
        typed.update({n.strip(): module for n in names.split(",")})
    assert typed == wavelength_pdf._API
    assert set(wavelength_pdf.__all__) == {"__version__", *typed}


def test_help_documents_every_public_name():
    text = pydoc.render_doc(wavelength_pdf, renderer=pydoc.plaintext)
    for name in wavelength_pdf._API:
        obj = getattr(wavelength_pdf, name)
        assert (obj.__doc__ or "").strip(), f"wavelength_pdf.{name} has no docstring"
        assert re.search(rf"\b{name}\b", text), f"help(wavelength_pdf) does not show {name}"
    for fn in ("optimize_spectrum", "evaluate_table", "load_spectrum", "read_table"):
        assert "Parameters" in getattr(wavelength_pdf, fn).__doc__ or "``" in getattr(wavelength_pdf, fn).__doc__


def test_version_is_one_in_pyproject_package_and_changelog():
    version = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]
    assert wavelength_pdf.__version__ == version
    changelog = (REPO / "CHANGELOG.md").read_text()
    headings = re.findall(r"^## \[([^\]]+)\]", changelog, flags=re.M)
    assert headings[0] == "Unreleased", headings
    assert headings[1] == version, "the newest release in CHANGELOG.md is not the package's version"
    assert re.search(rf"^## \[{re.escape(version)}\] - \d{{4}}-\d{{2}}-\d{{2}}$", changelog, flags=re.M)
    assert f"v{version}" in changelog and "git tag -a" in changelog  # how the tags are made
