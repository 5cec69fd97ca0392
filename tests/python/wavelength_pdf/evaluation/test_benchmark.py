"""The benchmark (design §6.7): its measures on synthetic images, its grid, and its small
version end to end with the real renderer (tiny images): every sampler row unbiased, the
visible table matching pbrt-v4's own visible sampling, the measures agreeing with each other,
and a second run rendering nothing."""
from __future__ import annotations

import numpy as np
import pytest

from wavelength_pdf.evaluation.benchmark import grid as G
from wavelength_pdf.evaluation.benchmark import measures as M
from wavelength_pdf.table import read_table


def _image(rng, shape=(40, 50), level=0.3):
    return level * (0.5 + rng.random(shape + (3,)))


# --- Measures --------------------------------------------------------------------------


def test_pair_mse_is_the_variance_of_one_image():
    """Two independent images with per-pixel noise of variance s^2: (a - b)^2 / 2 estimates
    s^2, with no reference involved."""
    rng = np.random.default_rng(1)
    exact = _image(rng)
    s = 0.02
    a = exact + s * rng.standard_normal(exact.shape)
    b = exact + s * rng.standard_normal(exact.shape)
    truth = M.Truth.of(exact, exact, exact)
    m = M.pair(a, b, truth)
    assert m["mse"] == pytest.approx(s * s, rel=0.05)
    # Against an exact reference, the squared CIEDE2000 of one image and the seed-pair figure
    # measure the same thing (to first order in the noise).
    assert m["de2_ref"] == pytest.approx(m["de2"], rel=0.1)
    assert m["de"] > 0 and m["chroma2"] > 0 and m["chroma2"] < m["de2"] * 10


def test_reference_noise_subtracts():
    """A noisy reference inflates the error against it by its own noise, which its two halves
    measure: de2_ref (noise subtracted) stays at the seed-pair figure."""
    rng = np.random.default_rng(2)
    exact = _image(rng)
    s, st = 0.02, 0.015
    a, b = (exact + s * rng.standard_normal(exact.shape) for _ in range(2))
    h1, h2 = (exact + st * np.sqrt(2) * rng.standard_normal(exact.shape) for _ in range(2))
    truth = M.Truth.of((h1 + h2) / 2, h1, h2)
    m = M.pair(a, b, truth)
    assert truth.de2 > 0.2 * m["de2"]  # the reference's noise is not negligible here ...
    assert m["de2_ref"] == pytest.approx(m["de2"], rel=0.1)  # ... and is subtracted


def test_bias_z_sees_a_bias_and_not_noise():
    rng = np.random.default_rng(3)
    exact = _image(rng)
    noisy = lambda: exact + 0.05 * rng.standard_normal(exact.shape)  # noqa: E731
    assert np.all(np.abs(M.bias_z(noisy(), noisy(), exact)) < 4)
    assert np.all(np.abs(M.bias_z(noisy() * 1.05, noisy() * 1.05, exact)) > 6)


def test_lit_pixels_leave_out_emitters_seen_directly():
    img = np.full((10, 10, 3), 0.2)
    img[0, :3] = 50.0  # the lamp
    mask = M.lit_pixels(img)
    assert mask.sum() == 97 and not mask[0, :3].any()


def test_shares_and_equal_time():
    assert M.removed_share(1.0, 10.0, 1.0) == 1.0
    assert M.removed_share(10.0, 10.0, 1.0) == 0.0
    assert M.removed_share(5.5, 10.0, 1.0) == pytest.approx(0.5)
    assert np.isnan(M.removed_share(1.0, 1.0, 1.0))
    # A sampler with half the error at twice the time per sample is even at equal time.
    assert M.equal_time_ratio(0.5, 2.0, 1.0, 1.0) == pytest.approx(1.0)
    assert M.equal_time_ratio(0.5, 2.0, 1.0, 1.0, slope=2.0) == pytest.approx(2.0)


# --- Grid ------------------------------------------------------------------------------


def test_share_above_floor_and_its_standard_error():
    # Every pair alike: the share exactly, no spread.
    assert M.share_above_floor([2.0] * 4, [4.0] * 4, [1.0] * 4) == (pytest.approx(1 / 3), 0.0)
    share, se = M.share_above_floor([2.0], [4.0], [1.0])
    assert share == pytest.approx(1 / 3) and np.isnan(se)
    assert np.isnan(M.share_above_floor([2.0, 2.0], [1.0, 1.0], [1.0, 1.0])[0])  # nothing above the floor
    with pytest.raises(ValueError, match="pairs"):
        M.share_above_floor([1.0, 2.0], [3.0], [1.0, 1.0])
    # K pairs of noisy measures (relative noise 10 %, a pair's de2 scattering so): over many
    # repetitions the shares scatter by what the jackknife says, and centre on the true share.
    rng = np.random.default_rng(3)
    k, reps, true = 8, 4000, (1.5 - 1.0) / (2.5 - 1.0)
    draws = [M.share_above_floor(*(m * rng.gamma(100.0, 0.01, k) for m in (1.5, 2.5, 1.0)))
             for _ in range(reps)]
    shares, ses = np.array(draws).T
    assert abs(np.mean(shares) - true) < 0.01
    assert np.mean(ses) == pytest.approx(np.std(shares), rel=0.1)


def test_grid_has_the_lamps_and_scenes_it_promises():
    kinds = {}
    for lamp in G.LAMPS.values():
        kinds.setdefault(lamp.kind, []).append(lamp.key)
    assert len(kinds["LED"]) >= 4 and len(kinds["fluorescent"]) >= 4 and len(kinds["metal halide"]) >= 2
    assert {"cie-FL2", "cie-FL11", "2536", "cie-D65"} <= set(G.LAMPS)
    assert len(G.LAMPS) >= 12
    g = G.GridSpec(shared=G.SHARED)
    for lamp in ("2482", "2641"):
        G.add(g, G.Job(G.SCENES["cornell-box"], G.LAMPS[lamp], sweep="lamps", spp=(16, 64)))
    G.add(g, G.Job(G.SCENES["cornell-box"], G.LAMPS["2482"], sweep="scenes"))
    if G.SCENES["cornell-box"].available(G.SHARED):
        # The same job in both sweeps runs once, with both sweeps' sample counts.
        assert [j.name for j in g.jobs] == ["cornell-box/2482/sobol", "cornell-box/2641/sobol"]
        assert g.jobs[0].sweep == "lamps+scenes" and g.jobs[0].spp == (16, 64, 256)
        assert [j.name for j in G.select(g, ["scenes"]).jobs] == ["cornell-box/2482/sobol"]
    else:
        assert not g.jobs and len(g.skipped) == 3


def test_rows_can_be_narrowed_and_the_lamp_sweep_has_a_floor_at_each_spp():
    g = G.small_grid()
    assert G.with_rows(g, None) is g
    narrow = G.with_rows(g, ["spd", "optimized"])
    # Each job keeps only the named rows it had (the small grid has no optimized row), in its order.
    assert [j.rows for j in narrow.jobs] == [("spd",)] * len(g.jobs)
    assert [j.name for j in narrow.jobs] == [j.name for j in g.jobs]
    assert [j.floor_spp for j in narrow.jobs] == [j.floor_spp for j in g.jobs]
    with pytest.raises(ValueError, match="unknown rows floor, sdp"):
        G.with_rows(g, ["spd", "sdp", "floor"])
    # Every job of the lamp sweep, on both scenes, is measured against a floor of its own at
    # each of the sweep's spp (16 and 64; a job also in the scene sweep renders at 256 too).
    jobs = G.select(G.full_grid(), ["lamps"]).jobs
    assert {j.scene.key for j in jobs} == {s for s in G.LAMP_SWEEP_SCENES if G.SCENES[s].available()}
    for j in jobs:
        assert {16, 64} <= set(j.floor_spp), j.name


def test_wavelength_net_reaches_every_render_of_a_job(tmp_path):
    """benchmark --wavelength-net: the rows, the floor and the reference's chunks all render
    with it; without it none does."""
    from wavelength_pdf.evaluation.benchmark import run

    g = G.small_grid()
    assert G.with_wavelength_net(g, False) is g
    for on in (False, True):
        job = G.with_wavelength_net(g, on).jobs[0]
        p = run.plan_job(job, tmp_path / str(on), G.SHARED, None)
        renders = p.renders()
        assert len(renders) == len(p.images) + len(p.floor) + len(p.truth_chunks) > 0
        assert all(("--wavelength-net" in r.sampler.args) == on for r in renders)


def test_benchmark_refuses_unknown_rows_before_any_work(tmp_path, capsys):
    from wavelength_pdf.cli import main

    assert main(["benchmark", "--sweep", "small", "-o", str(tmp_path / "out"), "--rows", "spd", "nonsense"]) == 2
    assert "--rows: unknown rows nonsense" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_optimized_rows_name_the_colours_their_tables_are_made_for(tmp_path):
    """The optimizer's inputs per row: white for the lamp's tables, the scene's colours for the
    scene rows, the ColorChecker's 24 patches for the generic-colour row (a lamp table, in
    the lamp's folder, on the scene sweep's low-discrepancy jobs only)."""
    from types import SimpleNamespace

    from wavelength_pdf.evaluation.benchmark import run
    from wavelength_pdf.spectra import load_spectrum

    p = SimpleNamespace(reflectances="the scene's colours")
    assert run._made_by("optimized", p) == (None, "J")
    assert run._made_by(G.PIXEL, p) == (None, "stratified")
    assert run._made_by(G.SCENE_COLOURS, p) == ("the scene's colours", "J")
    assert run._made_by(G.PIXEL_SCENE, p) == ("the scene's colours", "stratified")
    colours, objective = run._made_by(G.GENERIC_COLOURS, p)
    assert (colours.name, len(colours), objective) == ("colorchecker", 24, "J")
    job = G.Job(G.SCENES["cornell-box"], G.LAMPS["2482"], rows=(G.GENERIC_COLOURS,))
    folder = run.lamp_folder(tmp_path, job)
    paths = run.baseline_tables(load_spectrum("cie:FL2"), folder, job.rows, job, tmp_path)
    # Named in the lamp's folder, left to the optimizer (not written as a simple table).
    assert paths[G.GENERIC_COLOURS] == tmp_path / "tables" / "2482" / f"{G.GENERIC_COLOURS}.csv"
    assert not paths[G.GENERIC_COLOURS].exists() and paths["spd"].is_file()
    g = G.full_grid()
    for j in g.jobs:
        if "scenes" in j.sweep.split("+"):
            assert (G.GENERIC_COLOURS in j.rows) == (j.pixel_sampler == "sobol"), j.name


def test_summary_by_regime():
    """The regime summary's medians come from the jobs' own ratios: a job whose table has a
    quarter of the best simple sampler's error and one where it has the same."""
    from wavelength_pdf.evaluation.benchmark import report

    def row(job, name, de2):
        return {"job": job, "sweep": "scenes", "kind": "fluorescent", "pixel_sampler": "sobol", "row": name,
                "spp": 64, "de2": de2, "share_removed_de2": 0.5}

    rows = [row("a/x/sobol", "optimized", 1.0), row("a/x/sobol", "uniform", 8.0), row("a/x/sobol", "spd", 4.0),
            row("b/x/sobol", "optimized", 2.0), row("b/x/sobol", "uniform", 2.0), row("b/x/sobol", "spd", 3.0)]
    table = report.summary_table(rows, 64)
    line = next(x for x in table.splitlines() if x.startswith("| fluorescent, sobol"))
    cells = [c.strip() for c in line.split("|")[1:-1]]
    assert cells[1] == "2"                      # jobs
    assert cells[2] == "2.50 (1.00-4.00)"       # best simple / table: 4 and 1
    assert cells[-1] == "1 of 2"                # pays on one job


def test_against_the_floor():
    """A table's error above the floor as a share of the best simple sampler's: the floor
    scaled from a lower spp as 1 / spp; a job with nothing to gain is counted apart."""
    from wavelength_pdf.evaluation.benchmark import report

    def row(job, name, spp, de2):
        return {"job": job, "sweep": "lamps", "kind": "sodium", "pixel_sampler": "sobol", "row": name,
                "spp": spp, "de2": de2, "share_removed_de2": 0.5}

    rows = [row("a/x/sobol", "floor", 16, 4.0), row("a/x/sobol", "spd", 64, 5.0),
            row("a/x/sobol", "optimized", 64, 2.0), row("a/x/sobol", G.PIXEL, 64, 3.0),
            row("b/x/sobol", "floor", 64, 1.0), row("b/x/sobol", "spd", 64, 1.05),
            row("b/x/sobol", "optimized", 64, 1.0), row("b/x/sobol", G.PIXEL, 64, 1.0)]
    assert report.floor_at(rows, "a/x/sobol", 64) == 1.0   # 4 x 16 / 64
    assert report.floor_at(rows, "a/x/sobol", 8) != report.floor_at(rows, "a/x/sobol", 8)  # none below
    assert report.above_floor_share(rows, "a/x/sobol", "optimized", 64) == 0.25  # (2 - 1) / (5 - 1)
    assert report.above_floor_share(rows, "a/x/sobol", G.PIXEL, 64) == 0.5
    assert np.isnan(report.above_floor_share(rows, "b/x/sobol", "optimized", 64))  # 1.05 is within 1.1x
    line = next(x for x in report.floor_table(rows, 64).splitlines() if x.startswith("| sodium"))
    cells = [c.strip() for c in line.split("|")[1:-1]]
    assert cells == ["sodium, sobol", "2", "1", "1 of 1", "0.25", "0 of 1", "0.50"]


# --- The small benchmark, end to end -----------------------------------------------------


@pytest.fixture(scope="module")
def small(tmp_path_factory, pbrt):
    from wavelength_pdf.evaluation.benchmark import run_benchmark

    out = tmp_path_factory.mktemp("benchmark")
    said: list[str] = []
    rows = run_benchmark(G.small_grid(), out, workers=2, pbrt=pbrt, say=said.append)
    return out, rows, said, pbrt


def _rows(rows, **what):
    return [r for r in rows if all(r[k] == v for k, v in what.items())]


def test_every_sampler_is_unbiased(small):
    """Image means agree with the reference's within noise, for every row at the higher spp
    (the reference is drawn with four other samplers, none of them the row's own table)."""
    _, rows, _, _ = small
    top = max(r["spp"] for r in rows)
    checked = _rows(rows, spp=top)
    assert {r["row"] for r in checked} >= {*G.SIMPLE, "start", G.BUILTIN, G.FLOOR}
    for r in checked:
        assert r["bias_z"] < 5, f"{r['job']} {r['row']}: |z| = {r['bias_z']:.2f}"


def test_visible_table_matches_pbrt_visible(small):
    """The visible table and pbrt-v4's own visible sampling have the same error within noise
    with independent pixel samples (the same four quantiles; with a stratified pixel sampler
    the table's order of u stratifies them better, so it can only do better there)."""
    _, rows, _, _ = small
    for r in _rows(rows, row="visible", pixel_sampler="independent"):
        b = _rows(rows, job=r["job"], row=G.BUILTIN, spp=r["spp"])[0]
        assert 1 / 1.8 < r["de2"] / b["de2"] < 1.8, (r["job"], r["spp"], r["de2"], b["de2"])


def test_measures_agree_and_sampling_the_lamp_pays(small):
    _, rows, _, _ = small
    agree = [r["de2_ref"] / r["de2"] for r in rows if r["de2"] > 0]
    assert 0.75 < np.median(agree) < 1.35
    # Under the tri-band lamp, stratified sampling of the lamp beats stratified uniform
    # sampling by a wide margin, and the floor is below every sampler.
    for r in _rows(rows, row="spd", spp=16):
        if r["lamp"] == "tri-band":
            u = _rows(rows, job=r["job"], row="uniform", spp=16)[0]
            f = _rows(rows, job=r["job"], row=G.FLOOR, spp=16)[0]
            assert u["de2"] > 2 * r["de2"] > 2 * 0.5 * f["de2"]


def test_the_image_row_is_the_predicted_best_of_its_candidates(small):
    """The IMAGE row (``choose --polish --spread``'s table) renders on the low-discrepancy job
    under one lamp only (not with independent samples, not under several kinds of light), with
    a table chosen for each spp it renders at, each of which records which candidate won and
    every candidate's prediction at that spp, the winner's the least; its images at an spp are
    rendered with that spp's table."""
    from wavelength_pdf.evaluation.benchmark import run
    from wavelength_pdf.evaluation.choose import CONTINUATION_SPP

    out, rows, _, pbrt = small
    assert max(G.small_grid().jobs[0].spp) < CONTINUATION_SPP
    assert {r["job"] for r in rows if r["row"] == G.IMAGE} == {"project-box/tri-band/sobol"}
    job = next(j for j in G.small_grid().jobs if j.name == "project-box/tri-band/sobol")
    folder = out / "jobs" / "project-box" / "tri-band" / "sobol"
    predictions = {}
    for spp in job.spp:
        note = next(c for c in read_table(folder / G.image_table_name(spp)).comments
                    if c.startswith(f"{G.IMAGE}: "))
        name, _, rest = note[len(G.IMAGE) + 2:].partition(", best of ")
        assert rest.split(" (")[0].endswith(f"at {spp} spp"), note
        predicted = dict(p.rsplit(" ", 1) for p in rest[rest.index("(") + 1:rest.rindex(")")].split(", "))
        # Both spp are below the continuation's: the spd table also polished at it first.
        assert set(predicted) == {*G.SIMPLE, "polished spd", f"polished spd via {CONTINUATION_SPP} spp"}
        assert name in predicted
        assert float(predicted[name]) == min(float(v) for v in predicted.values())
        predictions[spp] = predicted
    # Fewer samples, more wavelength noise: every simple sampler (one table at every spp; a
    # polished table is another table at each spp) is predicted worse at the lower spp.
    lo, hi = sorted(job.spp)[:2]
    assert all(float(predictions[lo][k]) > float(predictions[hi][k]) for k in G.SIMPLE)
    plan = run.plan_job(job, out, G.SHARED, pbrt)
    for (row, spp, _), r in plan.images.items():
        if row == G.IMAGE:
            assert r.sampler.args[r.sampler.args.index("--wavelength-pdf") + 1] == str(folder / G.image_table_name(spp))


def test_outputs_and_resume(small):
    from wavelength_pdf.evaluation.benchmark import run_benchmark

    out, rows, said, pbrt = small
    for name in ("results.csv", "report.md", "error-vs-spp.png"):
        assert (out / name).is_file()
    text = (out / "report.md").read_text()
    assert "## Checks" in text and "Regime map" in text and "## Summary by regime" in text
    again: list[str] = []
    rows2 = run_benchmark(G.small_grid(), out, workers=1, pbrt=pbrt, say=again.append)
    assert any("every render is done" in s for s in again), again
    assert [r["de2"] for r in rows2] == [r["de2"] for r in rows]
    # A grid stopped early: --no-render scores the finished jobs and names the others.
    victim = next((out / "jobs" / "two-lamp-box").rglob("renders/*.exr"))
    victim.unlink()
    partial: list[str] = []
    rows3 = run_benchmark(G.small_grid(), out, pbrt=pbrt, render=False, say=partial.append)
    assert {r["job"] for r in rows3} == {r["job"] for r in rows} - {"two-lamp-box/own/sobol"}
    assert any("not finished" in s and "two-lamp-box/own/sobol" in s for s in partial), partial
