"""The wheel as a pip user gets it (README, "Installing"): ``scripts/build_wheel.sh`` ships the
files git tracks and nothing else, the README's install line names the wheel it builds, and
the wheel installed into a fresh virtual environment runs ``optimize`` and ``show`` from a
folder outside the checkout; built ``--with-pbrt``, its ``wavelength-pdf`` finds the renderer
inside it with no configuration and renders the shipped Cornell box.

The wheels are built from a copy of the checkout (its tracked files, as they are now) that
also holds an untracked module in the package folder and a stale one where setuptools used to
leave its build (``build/lib``): neither may ship.
"""
from __future__ import annotations

import csv
import math
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path, PurePosixPath

import pytest

from repo_paths import REPO
from wheel_helpers import build_wheel, clean_env, fresh_venv

pytestmark = pytest.mark.slow

STRAY = "python/wavelength_pdf/_untracked_probe.py"
STALE = "build/lib/wavelength_pdf/_stale_probe.py"


@pytest.fixture(scope="module")
def checkout(tmp_path_factory) -> Path:
    """A git repository holding the checkout's tracked files, plus an untracked module and a
    stale build folder."""
    dest = tmp_path_factory.mktemp("checkout")
    tracked = subprocess.run(["git", "-C", str(REPO), "ls-files", "-z"], check=True, capture_output=True,
                             text=True).stdout.split("\0")
    for name in filter(None, tracked):
        src = REPO / name
        if src.is_file():  # a file deleted in the work tree and not yet committed is skipped
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    subprocess.run(["git", "init", "-q", str(dest)], check=True)
    subprocess.run(["git", "-C", str(dest), "add", "-A"], check=True)
    for name in (STRAY, STALE):
        (dest / name).parent.mkdir(parents=True, exist_ok=True)
        (dest / name).write_text("raise ImportError('this file must not ship')\n")
    return dest


@pytest.fixture(scope="module")
def wheel(checkout, tmp_path_factory) -> Path:
    return build_wheel(tmp_path_factory.mktemp("dist"), checkout=checkout)


def _source_of(member: str, checkout: Path) -> Path:
    """The file of ``checkout`` that the wheel's ``member`` is built from, through
    pyproject.toml's package-dir (the longest package prefix that maps a folder)."""
    setup = tomllib.loads((checkout / "pyproject.toml").read_text())["tool"]["setuptools"]
    parts = PurePosixPath(member).parts
    for n in range(len(parts) - 1, 0, -1):
        folder = setup["package-dir"].get(".".join(parts[:n]))
        if folder is not None:
            return checkout / folder / PurePosixPath(*parts[n:])
    return checkout / setup["package-dir"][""] / member


def test_the_wheel_holds_the_tracked_sources_and_nothing_else(checkout, wheel):
    tracked = set(subprocess.run(["git", "-C", str(checkout), "ls-files"], check=True, capture_output=True,
                                 text=True).stdout.splitlines())
    with zipfile.ZipFile(wheel) as z:
        members = [n for n in z.namelist() if not n.split("/")[0].endswith(".dist-info")]
        for member in members:
            source = _source_of(member, checkout)
            assert source.relative_to(checkout).as_posix() in tracked, f"{member} is not from a tracked file"
            assert z.read(member) == source.read_bytes(), f"{member} differs from {source}"
    shipped = {_source_of(m, checkout).relative_to(checkout).as_posix() for m in members}
    modules = {t for t in tracked if t.startswith("python/wavelength_pdf/") and t.endswith(".py")}
    assert modules <= shipped, f"tracked modules missing from the wheel: {sorted(modules - shipped)}"
    assert not any("probe" in m for m in members)
    assert wheel.name.endswith("-py3-none-any.whl")
    # The stale folder is as it was: the build wrote nothing there.
    assert sorted(p.relative_to(checkout).as_posix() for p in (checkout / "build").rglob("*") if p.is_file()) \
        == [STALE]


def test_pip_wheel_in_the_checkout_leaves_build_alone(checkout, tmp_path):
    """`pip wheel .` (and so `pip install .`) in the checkout itself: the build backend builds
    in a temporary folder, so nothing lands in build/ (the renderer's) and the stale module
    setuptools would have left there does not ship."""
    run = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                          "-w", str(tmp_path), "."], cwd=checkout, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    (wheel,) = tmp_path.glob("wavelength_pdf-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "wavelength_pdf/cli/__init__.py" in names and not any("_stale_probe" in n for n in names)
    assert [p.relative_to(checkout).as_posix() for p in (checkout / "build").rglob("*") if p.is_file()] == [STALE]


def test_the_readme_install_line_names_the_wheel_the_script_builds(wheel):
    assert f'pip install "dist/{wheel.name}[evaluation,mitsuba]"' in (REPO / "README.md").read_text()


def test_no_install_line_asks_an_index_for_the_package():
    """The package is on no index: `pip install wavelength-pdf[...]` fails wherever it is
    written (documents, error messages)."""
    by_name = re.compile(r"pip install\s+['\"]?wavelength[-_]pdf(?=[\[\s'\"]|$)")  # not a wheel's file name
    files = [REPO / "README.md", REPO / "wavelength_table" / "README.md", *(REPO / "integrations").rglob("README.md"), *(REPO / "docs").rglob("*.md"),
             *(REPO / "python").rglob("*.py")]
    found = [f"{f.relative_to(REPO)}: {m.group(0)}" for f in files for m in by_name.finditer(f.read_text())]
    assert not found, found


def _run(cmd: list[str], cwd: Path, env: dict[str, str], timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def _installed(bin_dir: Path, work: Path, env: dict[str, str]) -> tuple[Path, Path, Path]:
    """The installed package's folder, shipped spectrum and shipped scene; the package is the
    fresh environment's, not the checkout's."""
    probe = _run([str(bin_dir / "python"), "-c",
                  "import wavelength_pdf; from wavelength_pdf import data; "
                  "print(wavelength_pdf.__file__); print(data.demo_spectrum()); print(data.demo_scene())"],
                 work, env)
    assert probe.returncode == 0, probe.stderr[-3000:]
    init, spectrum, scene = (Path(line) for line in probe.stdout.split())
    venv = bin_dir.parent.resolve()
    for path in (init, spectrum, scene):
        assert path.resolve().is_relative_to(venv) and not path.resolve().is_relative_to(REPO), path
        assert path.is_file(), path
    return init.parent, spectrum, scene


def test_the_installed_wheel_optimizes_and_shows_from_elsewhere(wheel, tmp_path):
    bin_dir = fresh_venv(tmp_path / "venv", wheel)
    work = tmp_path / "work"
    work.mkdir()
    env = clean_env(bin_dir)
    _, spectrum, scene = _installed(bin_dir, work, env)

    opt = _run([str(bin_dir / "wavelength-pdf"), "optimize", str(spectrum), "-o", "table.csv",
                "--grid-step", "20", "--max-evals", "30", "-q"], work, env)
    assert opt.returncode == 0, opt.stderr[-3000:]
    assert (work / "table.csv").is_file()
    show = _run([str(bin_dir / "wavelength-pdf"), "show", "table.csv", "--spectrum", str(spectrum)], work, env)
    assert show.returncode == 0, show.stderr[-3000:]
    assert "accepted" in show.stdout and spectrum.stem in show.stdout, show.stdout

    # No renderer anywhere: the command that needs one says where it looked and how to get one.
    if shutil.which("pbrt", path=env["PATH"]):
        pytest.skip("a pbrt on the system PATH: the no-renderer message cannot be checked")
    none = _run([str(bin_dir / "wavelength-pdf"), "optimize", str(scene), "--whole-scene", "-o", "w.csv"],
                work, env, timeout=120)
    assert none.returncode == 2, (none.returncode, none.stderr[-3000:])
    assert "_bin/pbrt" in none.stderr and "build_wheel.sh --with-pbrt" in none.stderr, none.stderr[-3000:]


def test_a_wheel_with_the_renderer_renders_the_shipped_scene(checkout, pbrt, tmp_path):
    wheel = build_wheel(tmp_path / "dist", checkout=checkout, pbrt=pbrt)
    assert not wheel.name.endswith("-any.whl"), "a wheel carrying a binary is tagged for its platform"
    bin_dir = fresh_venv(tmp_path / "venv", wheel)
    work = tmp_path / "work"
    work.mkdir()
    env = clean_env(bin_dir)
    package, spectrum, scene = _installed(bin_dir, work, env)
    bundled = package / "_bin" / "pbrt"
    assert bundled.read_bytes() == pbrt.read_bytes()

    found = _run([str(bin_dir / "python"), "-c",
                  "from wavelength_pdf.renderer import find_pbrt; print(find_pbrt())"], work, env)
    assert found.returncode == 0 and Path(found.stdout.strip()) == bundled, found.stdout + found.stderr[-2000:]

    # The shipped scene, through the command's own lookup (no --pbrt, nothing on PATH), tiny.
    table = _run([str(bin_dir / "wavelength-pdf"), "baseline", "spd", str(spectrum), "-o", "spd.csv"], work, env)
    assert table.returncode == 0, table.stderr[-3000:]
    ev = _run([str(bin_dir / "wavelength-pdf"), "evaluate", str(scene), str(spectrum), "--table", "spd.csv",
               "-o", "eval", "--spp", "4", "--truth-spp", "16", "--resolution", "16x16", "--nthreads", "2",
               "--methods", "uniform", "table"], work, env)
    assert ev.returncode == 0, ev.stderr[-3000:]
    with open(work / "eval" / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {r["method"] for r in rows} == {"uniform", "table"}, rows
    for r in rows:
        # A 4-spp image differs from its 16-spp truth: a positive, finite CIEDE2000 error.
        errors = [float(r[k]) for k in ("mean", "median", "p95")]
        assert all(math.isfinite(e) for e in errors) and errors[0] > 0, r
        assert int(r["spp"]) == 4 and float(r["seconds"]) > 0, r
