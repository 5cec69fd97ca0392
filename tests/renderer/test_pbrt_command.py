"""The renderer's command line: ``--version``, ``-h`` / ``--help`` and an unknown flag."""
from __future__ import annotations

import re
import subprocess

import pytest

try:
    import tomllib
except ImportError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")


def run(pbrt, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(pbrt), *args], capture_output=True, text=True, timeout=60)


def test_version_is_the_projects(pbrt, repo):
    version = tomllib.loads((repo / "pyproject.toml").read_text())["project"]["version"]
    r = run(pbrt, "--version")
    assert r.returncode == 0, r.stderr
    assert re.match(rf"pbrt \(wavelength-pdf\) {re.escape(version)}\b", r.stdout), r.stdout


@pytest.mark.parametrize("flag", ["-h", "--help"])
def test_help_prints_usage_and_succeeds(pbrt, flag):
    r = run(pbrt, flag)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("usage: pbrt"), r.stdout
    for option in ("--spp", "--wavelength-pdf", "--version", "--help"):
        assert option in r.stdout


@pytest.mark.parametrize("flag", ["--no-such-flag", "-x"])
def test_unknown_flag_prints_usage_and_fails(pbrt, flag):
    r = run(pbrt, flag)
    assert r.returncode == 1
    assert f'unknown option "{flag}"' in r.stderr
    assert "usage: pbrt" in r.stderr
    assert r.stdout == ""
