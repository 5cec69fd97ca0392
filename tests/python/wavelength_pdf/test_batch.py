"""``batch --jobs N`` stopped from outside: its worker processes end with it.

A worker busy optimizing does not look at its parent, so a batch killed while its workers
ran left them running to the end of their jobs (60-90 s and ~380 MB each). Each test starts
a real batch of three lamps with two workers, waits until both workers run, stops the batch
process and checks that the workers are gone within seconds.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from repo_paths import REPO

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="reads the process table from /proc")


def _children(pid: int) -> list[int]:
    """The spawned worker processes (multiprocessing's spawn_main) whose parent is ``pid``."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        if ppid == pid and b"spawn_main" in cmdline:
            out.append(int(entry.name))
    return out


def _running(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for a reaper does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


def _default_sigint() -> None:
    """In the child: SIGINT's default action. A suite started in the background (`cmd &`)
    hands its children SIGINT ignored, which Python then keeps: Ctrl-C would do nothing."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start_batch(tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("tri-band-fluorescent.spd", "high-pressure-sodium.spd", "sodium-2nm-line.spd"):
        (folder / name).write_bytes((REPO / "spectra" / name).read_bytes())
    env = dict(os.environ, WAVELENGTH_PDF_JAX_CACHE="off",
               PYTHONPATH=os.pathsep.join([str(REPO / "python"), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, "-m", "wavelength_pdf", "batch", str(folder), "-o",
                             str(tmp_path / "out"), "--jobs", "2", "--quiet"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, preexec_fn=_default_sigint)
    deadline = time.monotonic() + 120
    workers: list[int] = []
    while time.monotonic() < deadline and proc.poll() is None:
        workers = _children(proc.pid)
        if len(workers) == 2:
            break
        time.sleep(0.2)
    assert len(workers) == 2 and proc.poll() is None, (workers, proc.poll())
    time.sleep(5)  # well into their work: importing JAX, compiling, optimizing
    assert all(_running(w) for w in workers), "a worker ended before the batch was stopped"
    return proc, workers


def _assert_gone(workers: list[int], seconds: float = 20) -> None:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and any(_running(w) for w in workers):
        time.sleep(0.2)
    left = [w for w in workers if _running(w)]
    for w in left:  # do not leave them to the rest of the test session
        os.kill(w, signal.SIGKILL)
    assert not left, f"workers {left} still ran {seconds:g} s after the batch ended"


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_workers_die_when_the_batch_is_killed(tmp_path, sig):
    proc, workers = _start_batch(tmp_path)
    proc.send_signal(sig)
    proc.wait(timeout=30)
    _assert_gone(workers)


def test_interrupted_batch_stops_its_workers_at_once(tmp_path):
    """Ctrl-C (SIGINT): the batch ends with status 130 without waiting for the jobs."""
    proc, workers = _start_batch(tmp_path)
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    assert proc.returncode == 130, proc.stderr.read().decode(errors="replace")
    assert time.monotonic() - t0 < 20, "the batch waited for its workers' jobs"
    _assert_gone(workers)


def test_batch_refuses_a_lamp_beyond_the_table_end_before_optimizing(tmp_path):
    """The rule of optimize (design §3.3) in batch: an error row, no table, no optimization."""
    from wavelength_pdf.batch import run_batch

    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "red-edge.spd").write_text("".join(f"{760 + i / 10} 1\n" for i in range(401)))
    rows, _ = run_batch(folder, tmp_path / "out", lo=380.0, hi=780.0, grid="auto", solver=None,
                        seed=0)
    (row,) = rows
    assert row["status"] == "error", row
    assert "outside the table's range [380, 780] nm" in row["message"], row
    assert "--range 380 800" in row["message"], row
    assert not (tmp_path / "out" / "red-edge.csv").exists()
