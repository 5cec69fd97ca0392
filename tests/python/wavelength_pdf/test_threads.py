"""Reproducibility: the same input and seed give the same table on one and on two cores."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from wavelength_pdf.threads import pin_xla_threads


#: The command, run on the given CPUs (set in the child itself: no fork of this process).
_ON_CPUS = ("import os, sys; os.sched_setaffinity(0, {int(c) for c in sys.argv[1].split(',')}); "
            "from wavelength_pdf.cli import main; sys.exit(main(sys.argv[2:]))")


def _optimize(out, cpus, env):
    cmd = [sys.executable, "-c", _ON_CPUS, ",".join(map(str, sorted(cpus))), "optimize",
           "cie:FL11", "-o", str(out), "--grid-step", "5", "--max-evals", "150", "--quiet"]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def _rows(path):
    return [line for line in path.read_text().splitlines() if not line.startswith("#")]


@pytest.mark.slow
def test_one_and_two_cores_give_the_same_table(tmp_path):
    """Without pinning, XLA's thread pool follows the CPUs the process may use and
    OpenBLAS splits its products by thread: the first objective evaluation already differs
    in its last bits, and the tables after 150 evaluations differ."""
    cpus = sorted(os.sched_getaffinity(0))
    if len(cpus) < 2:
        pytest.skip("needs two CPUs to compare one- and two-core runs")
    env = {k: v for k, v in os.environ.items() if k not in ("PJRT_NPROC", "NPROC")}
    env["WAVELENGTH_PDF_JAX_CACHE"] = "off"  # nothing shared between the two runs
    runs = [_optimize(tmp_path / "one.csv", {cpus[0]}, env),
            _optimize(tmp_path / "two.csv", set(cpus[:2]), env)]
    for p in runs:
        _, err = p.communicate(timeout=900)
        assert p.returncode == 0, err[-2000:]
    one, two = _rows(tmp_path / "one.csv"), _rows(tmp_path / "two.csv")
    assert len(one) == 82, "header and 81 nodes"
    assert one == two


def test_pin_respects_the_users_setting(monkeypatch):
    monkeypatch.setenv("PJRT_NPROC", "3")
    assert pin_xla_threads() == 3
    assert os.environ["PJRT_NPROC"] == "3"
