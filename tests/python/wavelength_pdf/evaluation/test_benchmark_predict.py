"""Predicted against measured error ratios over a benchmark's jobs: the pipeline on
a tiny benchmark folder written here (no renders needed), and the script's refusal when the
benchmark's material is missing."""
from __future__ import annotations

import importlib.util
import shutil

import numpy as np
import pytest

from repo_paths import REPO
from wavelength_pdf import stratified
from wavelength_pdf.evaluation.benchmark import predict as BP
from wavelength_pdf.spectra import load_spectrum
from wavelength_pdf.table import write_table


def _script():
    spec = importlib.util.spec_from_file_location("predict_benchmark", REPO / "scripts" / "predict_benchmark.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _bench(tmp_path):
    """A benchmark folder with one job (the ColorChecker under CIE FL2, a lamp that needs no
    shared material) whose optimized table is a copy of its spd table."""
    lamp = load_spectrum("cie:FL2", 380.0, 780.0)
    folder = tmp_path / "out" / "tables" / "cie-FL2"
    folder.mkdir(parents=True)
    write_table(folder / "uniform.csv", stratified.uniform_table(380.0, 780.0))
    write_table(folder / "spd.csv", stratified.stratified_table(lamp, "spd", 380.0, 780.0))
    shutil.copyfile(folder / "spd.csv", folder / "optimized.csv")
    base = {"job": "colorchecker/cie-FL2/sobol", "scene": "colorchecker", "lamp": "cie-FL2",
            "pixel_sampler": "sobol"}
    results = [dict(base, row=row, spp=16, de2=de2)
               for row, de2 in (("uniform", 3.0), ("spd", 1.1), ("optimized", 1.0), ("floor", 0.5))]
    return tmp_path / "out", results


def test_a_table_against_itself_is_ratio_one_and_uniform_is_worse(tmp_path):
    out, results = _bench(tmp_path)
    jobs, missing = BP.plan(results, out, tmp_path / "no-shared")
    assert missing == [] and len(jobs) == 1
    recs = BP.predict_jobs(results, jobs, (16,), BP.CANDIDATES)
    prs = {p["row"]: p for p in BP.pairs(recs, BP.CANDIDATES)}
    assert set(prs) == {"uniform", "spd"}
    assert prs["spd"]["measured"] == pytest.approx(1.1) and prs["uniform"]["measured"] == pytest.approx(3.0)
    for c in BP.CANDIDATES:
        assert prs["spd"][c] == 1.0, c  # the same table, whatever its file is called
        assert prs["uniform"][c] > 1.0, c


def test_scene_colours_are_each_jobs_materials(tmp_path, pbrt):
    """--colours scene: a job's predictions are those for its scene copy's own materials (as
    the renderer builds them), not the white surface's; an unknown colour set is refused."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.reflectances import scene_reflectances
    from wavelength_pdf.table import read_table

    out, results = _bench(tmp_path)
    folder = out / "jobs" / "colorchecker" / "cie-FL2" / "sobol"
    folder.mkdir(parents=True)
    scene = folder / "scene.pbrt"
    scene.write_bytes((REPO / "tests" / "data" / "scenes" / "two-lamps.pbrt").read_bytes())
    jobs, _ = BP.plan(results, out, tmp_path / "no-shared")
    white = BP.predict_jobs(results, jobs, (16,), ("covariance",))
    coloured = BP.predict_jobs(results, jobs, (16,), ("covariance",), "scene", out=out, pbrt=pbrt)
    lamp = load_spectrum("cie:FL2", 380.0, 780.0)
    materials = scene_reflectances(scene, pbrt=pbrt)
    for w, c in zip(white, coloured):
        table = read_table(jobs[0].tables[c["row"]])
        expected = P.covariance_de2(P.path_colours(table, lamp, materials), 16)
        assert c["covariance"] == pytest.approx(expected, rel=1e-9)
        assert c["covariance"] != pytest.approx(w["covariance"], rel=1e-3)
    with pytest.raises(ValueError, match="colours must be one of"):
        BP.predict_jobs(results, jobs, (16,), ("covariance",), "patches")


def test_a_missing_table_is_named(tmp_path):
    out, results = _bench(tmp_path)
    (out / "tables" / "cie-FL2" / "spd.csv").unlink()
    _, missing = BP.plan(results, out, tmp_path / "no-shared")
    assert len(missing) == 1 and "spd.csv" in missing[0]


def test_floor_scale_is_fitted_on_the_other_jobs():
    """Rows whose measured error is exactly 2 x prediction + floor: the scale fitted without
    each job is 2, and the floored prediction is the measurement; a job that breaks the
    rule is predicted from the others, not from itself."""
    recs = []
    for j, scale in (("a", 2.0), ("b", 2.0), ("c", 2.0), ("d", 50.0)):
        for row, pred in (("uniform", 3.0), ("optimized", 0.2)):
            recs.append({"job": j, "scene": "s", "regime": "scenes", "pixel_sampler": "sobol", "spp": 16,
                         "row": row, "covariance": pred, "floor": 0.1, "de2": scale * pred + 0.1})
    BP.add_floor(recs, ["covariance"])
    for r in recs:
        assert r["covariance+floor"] == pytest.approx(2.0 * r["covariance"] + 0.1), r


def test_summary_ranks():
    rng = np.random.default_rng(0)
    meas = np.exp(rng.normal(size=40))
    prs = [{"spp": 64, "row": "uniform", "regime": "scenes" if i % 2 else "colorchecker", "measured": m,
            "same": m, "reversed": 1.0 / m} for i, m in enumerate(meas)]
    s = {(x["candidate"], x["regime"]): x for x in BP.summary(prs, ["same", "reversed"])}
    assert s[("same", "all")]["spearman"] == pytest.approx(1.0) and s[("same", "all")]["log10_median"] == 0.0
    assert s[("reversed", "scenes")]["spearman"] == pytest.approx(-1.0)
    assert s[("same", "all")]["pairs"] == 40 and s[("same", "colorchecker")]["pairs"] == 20


def test_pairs_round_trip_and_pool_over_files(tmp_path, capsys):
    """prediction.csv reads back as written, and --pool ranks the pairs of several files
    together: two files whose predictions rank each file's pairs perfectly but sit at scales
    apart pool to less than 1."""
    from scipy.stats import spearmanr

    rng = np.random.default_rng(1)
    files, meas, pred = [], [], []
    for k, scale in enumerate((1.0, 30.0)):
        m = np.exp(rng.normal(size=12))
        prs = [{"job": f"s{k}/lamp/sobol", "regime": "scenes", "scene": f"s{k}", "lamp": "lamp",
                "pixel_sampler": "sobol", "spp": 64, "row": "uniform", "measured": float(x),
                "good": float(x * scale)} for x in m]
        path = tmp_path / f"prediction-{k}.csv"
        BP.write_csv(path, prs, ["good"])
        back, cands = BP.read_pairs(path)
        assert cands == ["good"] and len(back) == len(prs)
        assert [(p["spp"], p["row"]) for p in back] == [(64, "uniform")] * len(prs)
        np.testing.assert_allclose([p["good"] for p in back], [p["good"] for p in prs], rtol=1e-5)
        files.append(str(path))
        meas += list(m)
        pred += [x * scale for x in m]
    assert _script().main(["--pool", *files]) == 0
    expected = spearmanr(pred, meas).statistic
    assert expected < 0.99
    assert f"| good | {expected:.2f} (" in capsys.readouterr().out
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    assert _script().main(["--pool", files[0], str(tmp_path / "other.csv")]) == 2
    assert "other.csv: not a prediction.csv" in capsys.readouterr().err


def test_script_refuses_before_work_when_the_benchmark_is_missing(tmp_path, capsys):
    code = _script().main(["-o", str(tmp_path / "none"), "--shared", str(tmp_path / "none-shared"),
                           "--docs", str(tmp_path / "docs"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert "no benchmark tables" in err and "no shared material" in err
    assert not (tmp_path / "docs").exists()


def test_script_names_missing_tables(tmp_path, capsys):
    out, results = _bench(tmp_path)
    (out / "tables" / "cie-FL2" / "optimized.csv").unlink()
    import csv

    with open(out / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(results[0]))
        w.writeheader()
        w.writerows(results)
    (tmp_path / "shared").mkdir()
    code = _script().main(["-o", str(out), "--shared", str(tmp_path / "shared"), "--docs", str(tmp_path / "docs"),
                           "--quiet"])
    assert code == 2 and "optimized table" in capsys.readouterr().err


def test_pixel_colours_come_from_one_render_of_the_scene(tmp_path, pbrt):
    """--colours pixels: one render of the scene under a flat lamp with a spectral film gives
    every lit pixel's spectrum. Its buckets and its RGB, two independent paths through the
    renderer's film, give the same luminance (the scale that puts the buckets in the image's
    units is 1 within 2 %); the copy of the spd table predicts exactly the spd table's error,
    uniform sampling more, with each pixel's incoherence or its spread; only the linearised
    candidates are offered."""
    from wavelength_pdf.evaluation import transfer

    out, results = _bench(tmp_path)
    tr = BP.scene_transfer("colorchecker", out, pbrt=pbrt, spp=64)
    assert tr.scale == pytest.approx(1.0, rel=0.02)
    assert tr.t.shape == (int(tr.mask.sum()), transfer.BUCKETS) and np.all(tr.t >= 0)
    assert np.all(np.isfinite(tr.incoherence)) and np.all(tr.incoherence >= 0)
    jobs, _ = BP.plan(results, out, tmp_path / "no-shared")
    recs = BP.predict_jobs(results, jobs, (16,), BP.PIXEL_CANDIDATES, "pixels", out=out, pbrt=pbrt)
    prs = {p["row"]: p for p in BP.pairs(recs, BP.PIXEL_CANDIDATES)}
    for c in BP.PIXEL_CANDIDATES:
        assert prs["spd"][c] == 1.0 and prs["uniform"][c] > 1.0, c
    with pytest.raises(ValueError, match="only covariance"):
        BP.predict_jobs(results, jobs, (16,), ("J",), "pixels", out=out, pbrt=pbrt)
    # With each pixel's spread in place of its incoherence: the same properties, other values.
    spread = BP.predict_jobs(results, jobs, (16,), BP.PIXEL_CANDIDATES, "pixels", out=out, pbrt=pbrt, spread=True)
    prs_spread = {p["row"]: p for p in BP.pairs(spread, BP.PIXEL_CANDIDATES)}
    for c in BP.PIXEL_CANDIDATES:
        assert prs_spread["spd"][c] == 1.0 and prs_spread["uniform"][c] > 1.0, c
    assert prs_spread["uniform"]["covariance"] != pytest.approx(prs["uniform"]["covariance"], rel=1e-3)
    with pytest.raises(ValueError, match="spread"):
        BP.predict_jobs(results, jobs, (16,), ("covariance",), "white", spread=True)


def test_a_scene_lit_by_lamps_of_several_kinds_has_no_transfer(tmp_path):
    from wavelength_pdf.evaluation import transfer
    from wavelength_pdf.evaluation.benchmark import grid as G

    with pytest.raises(ValueError, match="own lamps"):
        BP.scene_transfer("night-street", tmp_path)
    with pytest.raises(ValueError, match="3 kinds of light"):
        transfer.one_kind(G.SCENES["night-street"].path())
    assert transfer.one_kind(G.SCENES["colorchecker"].path()).values.max() > 0


def test_an_rgb_image_has_no_spectral_buckets(tmp_path):
    from wavelength_pdf.exr import ImageError, read_spectral, write_rgb

    write_rgb(tmp_path / "rgb.exr", np.ones((2, 3, 3)))
    with pytest.raises(ImageError, match="no spectral channels"):
        read_spectral(tmp_path / "rgb.exr")
    with pytest.raises(ImageError, match="no such image"):
        read_spectral(tmp_path / "missing.exr")


def test_the_film_marks_the_light_that_kept_one_wavelength(tmp_path, pbrt):
    """The spectral film's channel wavelengths.terminated: the share of a pixel's light carried
    by paths that kept one wavelength. The prism (dispersive glass) has pixels lit only
    through it and pixels it does not touch; a scene without dispersion has none."""
    import subprocess

    from wavelength_pdf.evaluation import transfer
    from wavelength_pdf.evaluation.benchmark import grid as G
    from wavelength_pdf.exr import read_channel

    shares = {}
    for scene in ("prism", "colorchecker"):
        f = transfer.copy_scene(G.SCENES[scene].path(), tmp_path / scene, G.SCENES[scene].resolution)
        subprocess.run([str(pbrt), "--quiet", "--spp", "16", "--outfile", str(tmp_path / f"{scene}.exr"), str(f)],
                       check=True)
        shares[scene] = read_channel(tmp_path / f"{scene}.exr", transfer.TERMINATED)
    prism = shares["prism"]
    assert prism.min() >= 0 and prism.max() <= 1
    assert np.mean(prism == 0) > 0.2 and np.mean(prism > 0.99) > 0.01
    assert np.all(shares["colorchecker"] == 0)


def test_the_choice_is_the_predicted_best_and_is_scored_against_the_best_simple_sampler():
    """choices(): per job and spp the row the prediction ranks first; its measured error
    beside the table's and the best simple sampler's, and whether each loses to the latter by
    more than 10 %."""
    def rec(job, row, de2, pred):
        return {"job": job, "scene": job.split("/")[0], "lamp": "L", "spp": 16, "row": row, "de2": de2, "p": pred}

    records = [rec("a/L/sobol", "optimized", 1.0, 1.0), rec("a/L/sobol", "spd", 1.2, 2.0),
               rec("a/L/sobol", "uniform", 3.0, 9.0),
               rec("b/L/sobol", "optimized", 2.0, 1.5), rec("b/L/sobol", "spd", 1.5, 1.0),
               rec("b/L/sobol", "uniform", 3.0, 9.0), rec("b/L/sobol", "start", 0.1, 0.1)]
    ch = {c["job"]: c for c in BP.choices(records, "p")}
    assert ch["a/L/sobol"]["chosen"] == "optimized" and not ch["a/L/sobol"]["table_worse"]
    b = ch["b/L/sobol"]
    assert b["chosen"] == "spd"  # "start" is not a candidate: the table or a simple sampler
    assert b["table_worse"] and not b["chosen_worse"] and b["de2_best_simple"] == 1.5
    assert "| 16 | 2 | 1 | 0 |" in BP.choices_markdown(list(ch.values()))
