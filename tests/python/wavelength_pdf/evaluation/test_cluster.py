"""The evaluation grid on Dask: a scheduler and two workers on localhost give the same results
as a serial run with the same seeds; a ground truth merged from chunks is their spp-weighted
mean; killing a worker mid-grid loses no finished render; renders are written atomically."""
from __future__ import annotations

import csv
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf.cli import main
from wavelength_pdf.cli import evaluate as commands
from wavelength_pdf.evaluation import cluster, render as rendering
from wavelength_pdf.evaluation.protocol import Config, evaluate, merge_chunks, merge_truth, plan
from wavelength_pdf.exr import read_rgb
from wavelength_pdf.spectra import load_spectrum
from repo_paths import REPO  # noqa: E402

TABLE = REPO / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
DASK = Path(sys.executable).parent / "dask"


@pytest.fixture(scope="module")
def cornell(repo: Path) -> Path:
    return repo / "scenes" / "cornell-box" / "scene.pbrt"


@pytest.fixture(scope="module")
def spd(repo: Path) -> str:
    return str(repo / "spectra" / "tri-band-fluorescent.spd")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _workers(address: str) -> int:
    from distributed import Client

    with Client(address, timeout="10s") as c:
        return len(c.scheduler_info(n_workers=-1)["workers"])


@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, each in its own process
    group (so that killing one takes its renders with it); all torn down in the end. Shared by
    the module's tests (starting workers is the slow part); the test that kills one runs last."""
    assert DASK.is_file(), f"{DASK} is missing: pip install 'dask[distributed]'"
    tmp_path = tmp_path_factory.mktemp("dask")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    logs = tmp_path / "dask-logs"
    logs.mkdir()
    procs = []

    def start(name, *args):
        log = open(logs / f"{name}.log", "w")
        procs.append(subprocess.Popen([str(DASK), *args], stdout=log, stderr=subprocess.STDOUT,
                                      cwd=tmp_path, start_new_session=True))
        log.close()

    try:
        start("scheduler", "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")
        for i in range(2):
            start(f"worker{i}", "worker", address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard",
                  "--host", "127.0.0.1", "--local-directory", str(tmp_path / f"w{i}"), "--death-timeout", "120")
        deadline = time.monotonic() + 120
        while True:
            try:
                if _workers(address) == 2:
                    break
            except OSError:
                pass
            if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                text = "\n".join(f.read_text()[-2000:] for f in logs.iterdir())
                pytest.fail(f"the local Dask cluster did not come up:\n{text}")
            time.sleep(0.5)
        yield address, procs[1:]
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


@pytest.fixture
def no_colour_bars(monkeypatch):
    """The jobs' colour bar and densities plots are not what these tests check, and computing
    them (JAX compilation) is most of a tiny grid's time: leave them out."""
    from wavelength_pdf import plots  # the commands import it where they draw

    drawn = []
    monkeypatch.setattr(plots, "colour_bar_png", lambda path, *a: drawn.append(path))
    monkeypatch.setattr(plots, "densities_png", lambda path, *a: drawn.append(path))
    return drawn


def _rows(path: Path) -> list[dict]:
    """results.csv without the render times (wall clock differs between runs)."""
    with open(path, newline="") as f:
        return [{k: v for k, v in r.items() if k != "seconds"} for r in csv.DictReader(f)]


def _grid_args(out: Path, cornell: Path, spd: str, *extra: str) -> list[str]:
    return ["grid", "--pairs", f"{cornell}={spd}", "-o", str(out), "--resolution", "12x12", "--spp", "4", "16",
            "--truth-spp", "256", "--truth-chunks", "4", "--seeds", "2", *extra]


def _with_table(out: Path) -> None:
    """The job's table, ready (a cached table is reused), so the test spends no time optimizing."""
    folder = out / "cornell-box" / "tri-band-fluorescent"
    folder.mkdir(parents=True)
    shutil.copy(TABLE, folder / "table.csv")


def test_merge_chunks_is_the_spp_weighted_mean() -> None:
    rng = np.random.default_rng(3)
    images = [rng.random((5, 7, 3)).astype(np.float32) for _ in range(4)]
    spp = [1, 3, 4, 8]
    merged = merge_chunks(images, spp)
    expect = sum(s * im.astype(np.float64) for s, im in zip(spp, images)) / sum(spp)
    np.testing.assert_allclose(merged, expect, rtol=1e-12)
    # equal weights: the plain mean; one chunk: itself
    np.testing.assert_allclose(merge_chunks(images, [2] * 4), np.mean(images, axis=0, dtype=np.float64), rtol=1e-12)
    np.testing.assert_array_equal(merge_chunks(images[:1], [5]), images[0])
    for bad in (([], []), (images, [1, 2]), (images, [1, 0, 1, 1]), (images[:2], [1, np.nan])):
        with pytest.raises(ValueError, match="merge_chunks"):
            merge_chunks(*bad)
    with pytest.raises(ValueError, match="shapes"):
        merge_chunks([images[0], images[1][:2]], [1, 1])


def test_truth_from_four_chunks_is_the_weighted_mean_of_their_images(tmp_path, cornell, pbrt) -> None:
    lamp = load_spectrum(str(cornell.parents[2] / "spectra" / "tri-band-fluorescent.spd"), lo=380, hi=780)
    config = Config(spp=(4,), methods=("uniform",), truth_spp=64, truth_chunks=4, truth_method="uniform",
                    resolution=(10, 8), nthreads=1, pbrt=pbrt)
    p = plan(cornell, lamp, tmp_path, config, table=TABLE)
    assert [j.spp for j in p.truth_chunks] == [16] * 4 and len({j.seed for j in p.truth_chunks}) == 4
    chunks = [j.run(1) for j in p.truth_chunks]
    truth = merge_truth(chunks, p.truth_chunks, p.truth)
    images = [read_rgb(c.image).astype(np.float64) for c in chunks]
    assert not np.allclose(images[0], images[1])  # different seeds, different noise
    np.testing.assert_allclose(read_rgb(truth.image), sum(16 * im for im in images) / 64, rtol=1e-6, atol=1e-7)
    assert truth.seconds == pytest.approx(sum(c.seconds for c in chunks))
    stamp = truth.image.stat().st_mtime_ns
    assert merge_truth(chunks, p.truth_chunks, p.truth).image.stat().st_mtime_ns == stamp  # cached
    with pytest.raises(ValueError, match="--truth-chunks"):
        plan(cornell, lamp, tmp_path, Config(truth_spp=64, truth_chunks=3, pbrt=pbrt), table=TABLE)


def test_grid_on_a_scheduler_and_two_workers_equals_a_serial_run(tmp_path, dask_cluster, cornell, spd,
                                                                  pbrt, capsys, no_colour_bars) -> None:
    address, _ = dask_cluster
    out = tmp_path / "dist"
    _with_table(out)
    assert main(_grid_args(out, cornell, spd, "--scheduler", address, "--pbrt", str(pbrt))) == 0
    err = capsys.readouterr().err
    assert "estimated CPU time" in err and "16 of 16 renders to do" in err  # 4 chunks + 3 x 2 x 2 images
    serial = Config(spp=(4, 16), truth_spp=256, truth_chunks=4, resolution=(12, 12), seeds=2, nthreads=2,
                    pbrt=pbrt)
    evaluate(cornell, load_spectrum(spd, lo=380, hi=780), tmp_path / "serial", serial, table=TABLE)
    dist = _rows(out / "results.csv")
    assert len(dist) == 6 and dist == _rows(tmp_path / "serial" / "results.csv")
    assert dist == _rows(out / "cornell-box" / "tri-band-fluorescent" / "results.csv")
    # no temporary file is left behind, and a rerun renders nothing again
    assert not list(out.rglob(".*.tmp*"))
    assert main(_grid_args(out, cornell, spd, "--scheduler", address, "--pbrt", str(pbrt))) == 0
    assert "estimated" not in capsys.readouterr().err


def test_render_threads_share_a_host_s_cores() -> None:
    assert cluster.render_threads(8, 8) == 1
    assert cluster.render_threads(8, 2) == 4
    assert cluster.render_threads(2, 3) == 1  # oversubscribed: still one thread
    assert cluster.render_threads(16, 0) == 16


def test_the_estimate_fits_start_up_and_time_per_sample() -> None:
    cost = cluster.fit_cost([(8, 2, 1.0 + 8 * 0.25), (1, 2, 1.0 + 0.25)])
    assert cost.start == pytest.approx(1.0) and cost.per_spp == pytest.approx(0.25) and cost.threads == 2
    assert cost.cpu_seconds(100) == pytest.approx(1.0 + 0.25 * 100 * 2)
    noisy = cluster.fit_cost([(1, 1, 2.0), (8, 1, 1.5)])  # the longer probe ran faster: no negative cost
    assert noisy.per_spp == 0 and noisy.start == pytest.approx(2.0)


def test_sweep_removes_only_idle_temporary_files(tmp_path) -> None:
    old, new, image = (tmp_path / n for n in (".a.1234.tmp.exr", ".b.5678.tmp.exr", "a.exr"))
    for f in (old, new, image):
        f.write_text("x")
    os.utime(old, (time.time() - 100, time.time() - 100))
    os.utime(image, (time.time() - 100, time.time() - 100))
    assert cluster.sweep(tmp_path, time.time() - 10) == [old]
    assert sorted(p.name for p in tmp_path.iterdir()) == [new.name, image.name]


def test_a_failed_render_leaves_no_file(tmp_path, pbrt) -> None:
    bad = tmp_path / "bad.pbrt"
    bad.write_text('WorldBegin\nShape "sphere" "float radius" [ oops ]\n')
    uniform = rendering.samplers(None, 380, 780)["uniform"]
    with pytest.raises(rendering.RenderError, match=r"bad\.pbrt:2"):
        rendering.render(bad, tmp_path / "b.exr", uniform, 4, pbrt=pbrt)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.pbrt"]


def _finished(renders: Path) -> dict[str, int]:
    """The finished renders' records by name, with their modification times: not the hidden
    ``.NAME.PID.tmp.json`` a render is still writing (pathlib's glob matches dot files), which
    a killed worker leaves to be swept (a flake under load: one was counted as finished)."""
    out = {}
    for m in renders.glob("*.json"):
        if not m.name.startswith("."):
            try:
                out[m.name] = m.stat().st_mtime_ns
            except FileNotFoundError:  # renamed or swept between the listing and the stat
                pass
    return out


def test_killing_a_worker_mid_grid_loses_no_finished_render(tmp_path, dask_cluster, cornell, spd, pbrt,
                                                            no_colour_bars) -> None:
    address, workers = dask_cluster
    out = tmp_path / "grid"
    _with_table(out)
    renders = out / "cornell-box" / "tri-band-fluorescent" / "renders"
    outcome = {}
    args = _grid_args(out, cornell, spd, "--scheduler", address, "--pbrt", str(pbrt), "--seeds", "3")
    grid = threading.Thread(target=lambda: outcome.setdefault("rc", main(args)))
    grid.start()
    try:
        deadline = time.monotonic() + 300
        while len(_finished(renders)) < 3 and grid.is_alive() and time.monotonic() < deadline:
            time.sleep(0.05)
        finished = _finished(renders)
        assert grid.is_alive(), "the grid finished before a worker could be killed"
        os.killpg(workers[0].pid, signal.SIGKILL)  # the worker, its nanny and its renders
        workers[0].wait()
    finally:
        grid.join(timeout=600)
    assert not grid.is_alive() and outcome.get("rc") == 0
    assert len(finished) >= 3
    after = _finished(renders)
    assert {k: after.get(k) for k in finished} == finished  # every finished render kept, none redone
    assert len(after) == 4 + 3 * 2 * 3 + 1  # every render and the merged truth
    rows = _rows(out / "results.csv")
    assert len(rows) == 6 and all(float(r["mean"]) > 0 and r["seeds"] == "3" for r in rows)
