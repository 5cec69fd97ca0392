"""The evaluation end to end on the project's Cornell box at a few pixels: every method and spp
gets an image, errors fall with spp, the table beats the baseline on a line lamp, renders
are reused on a rerun (resumable) and redone when an input changes, and the grid report
links files that exist."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf.cli import main
from wavelength_pdf.cli import evaluate as commands
from wavelength_pdf.evaluation import report
from wavelength_pdf.evaluation.protocol import Config, evaluate
from wavelength_pdf.spectra import load_spectrum
from wavelength_pdf.table import read_table, write_table
from repo_paths import REPO  # noqa: E402

TABLE = REPO / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"


@pytest.fixture(scope="module")
def cornell(repo: Path) -> Path:
    return repo / "scenes" / "cornell-box" / "scene.pbrt"


@pytest.fixture(scope="module")
def lamp(repo: Path):
    return load_spectrum(str(repo / "spectra" / "tri-band-fluorescent.spd"), lo=380, hi=780)


def _config(pbrt: Path, **kw) -> Config:
    base = dict(spp=(4, 64), truth_spp=2048, truth_method="table", resolution=(12, 12), seeds=2,
                nthreads=2, pbrt=pbrt)
    base.update(kw)
    return Config(**base)


def test_rows_errors_fall_and_the_table_beats_uniform(tmp_path, cornell, lamp, pbrt) -> None:
    ev = evaluate(cornell, lamp, tmp_path, _config(pbrt), table=TABLE)
    by = {(r.method, r.spp): r for r in ev.rows}
    assert set(by) == {(m, s) for m in ("uniform", "visible", "table") for s in (4, 64)}
    for r in ev.rows:
        assert (tmp_path / r.image).is_file() and r.seeds == 2
        assert np.isfinite(r.mean_sd) and r.mean_sd >= 0 and r.seconds > 0
        assert 0 <= r.median <= r.p95
    for m in ("uniform", "visible", "table"):
        assert by[(m, 64)].mean < by[(m, 4)].mean, m
    # The tri-band lamp is the method's case: its table's colour error is far below uniform's.
    for s in (4, 64):
        assert by[("table", s)].mean < 0.6 * by[("uniform", s)].mean, s
    assert (tmp_path / "results.csv").read_text().count("\n") == 1 + len(ev.rows)


def test_reruns_reuse_renders_and_a_changed_table_renders_again(tmp_path, cornell, lamp, pbrt) -> None:
    table = tmp_path / "t.csv"
    shutil.copy(TABLE, table)
    config = _config(pbrt, spp=(4,), truth_spp=64, seeds=1, methods=("uniform", "table"))
    evaluate(cornell, lamp, tmp_path / "ev", config, table=table)
    metas = sorted((tmp_path / "ev" / "renders").glob("*.json"))
    stamp = {m.name: m.stat().st_mtime_ns for m in metas}
    evaluate(cornell, lamp, tmp_path / "ev", config, table=table)
    assert {m.name: m.stat().st_mtime_ns for m in metas} == stamp  # nothing rendered again
    t = read_table(table)
    write_table(table, type(t)(grid=t.grid, pdfs=t.pdfs[::-1].copy()))  # same densities, new order
    evaluate(cornell, lamp, tmp_path / "ev", config, table=table)
    after = {m.name: m.stat().st_mtime_ns for m in metas}
    assert after["table-4-seed1.json"] != stamp["table-4-seed1.json"]
    assert after["uniform-4-seed1.json"] == stamp["uniform-4-seed1.json"]
    assert json.loads((tmp_path / "ev" / "renders" / "table-4-seed1.json").read_text())["seconds"] > 0


def test_grid_report_links_existing_files(tmp_path, cornell, repo, pbrt) -> None:
    # The tri-band table is given, so that the grid does not spend time optimizing.
    config = _config(pbrt, spp=(4,), truth_spp=64, seeds=1, nthreads=1)
    spd = str(repo / "spectra" / "tri-band-fluorescent.spd")
    rows = commands.run_grid([(cornell, spd)], tmp_path, config, "test grid", workers=1, tables={0: TABLE},
                             published=["9.9"])
    assert len(rows) == 3
    text = (tmp_path / "report.md").read_text()
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert len(links) == 4  # summary, and the job's colour bar, error plot and error maps
    for link in links:
        assert (tmp_path / link).is_file(), link
    assert "| cornell-box |" in text
    assert report.markdown_table(rows, published={("cornell-box", "tri-band-fluorescent"): "9.9"}) in text
    assert "published ratio" in text and text.count(" 9.9 |") == 1  # on the job's highest-spp line


def test_command_line_errors_exit_2_and_name_the_problem(tmp_path, capsys) -> None:
    assert main(["grid", "--pairs", "no-equals-sign", "-o", str(tmp_path)]) == 2
    assert "SCENE=SPECTRUM" in capsys.readouterr().err
    assert main(["grid", "--pairs", f"{tmp_path}/missing.pbrt=cie:D65", "-o", str(tmp_path)]) == 2
    assert "missing.pbrt" in capsys.readouterr().err
    assert main(["published", "--shared", str(tmp_path / "nowhere"), "-o", str(tmp_path)]) == 2
    assert "nowhere" in capsys.readouterr().err
    assert main(["evaluate", "x.pbrt", "cie:D65", "-o", str(tmp_path), "--seeds", "0"]) == 2
    # truth chunks of unequal spp, or no worker: an error before anything runs
    assert main(["grid", "--pairs", "x.pbrt=cie:D65", "-o", str(tmp_path), "--truth-spp", "100",
                 "--truth-chunks", "3"]) == 2
    assert "--truth-chunks" in capsys.readouterr().err
    assert main(["grid", "--pairs", "x.pbrt=cie:D65", "-o", str(tmp_path), "--workers", "0"]) == 2
    assert "--workers" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["evaluate", "x.pbrt", "cie:D65", "-o", str(tmp_path), "--resolution-scale", "-1"])


def test_published_jobs_exist_in_shared(shared) -> None:
    jobs = commands.published_jobs(shared)
    assert len(jobs) == len(commands.PUBLISHED) == len(commands.published_ratios()) == 14
    assert {p.parent.name for p, _ in jobs} == {"cornell-box", "teapot", "veach-bidir", "veach-mis", "staircase",
                                               "glass-of-water"}
    assert commands.published_ratios(["veach-mis/2641", "glass-of-water/cie:D65"]) == ["2.4", "0.93"]
    assert commands.published_jobs(shared, ["veach-mis/2641"])[0][1].endswith("2641.csv")
    with pytest.raises(ValueError, match="no job"):
        commands.published_jobs(shared, ["teapot/1"])


def test_ratio_error_matches_the_spread_of_simulated_seeds() -> None:
    from wavelength_pdf.evaluation.protocol import Row

    def row(mean, sd, seeds):
        return Row("s", "i", "m", 1, mean, mean, mean, 1.0, "x", seeds, sd)

    assert np.isnan(report.ratio_and_error(row(4.0, 0.1, 1), row(1.0, 0.1, 1))[1])
    # Means of 3 seeds each, drawn with the given per-seed spreads: the ratio's spread over many
    # draws matches the first-order standard error.
    rng = np.random.default_rng(5)
    n, sd_b, sd_o = 3, 0.2, 0.05
    ratios = rng.normal(4.0, sd_b, (20000, n)).mean(1) / rng.normal(1.0, sd_o, (20000, n)).mean(1)
    r, err = report.ratio_and_error(row(4.0, sd_b, n), row(1.0, sd_o, n))
    assert r == 4.0 and err == pytest.approx(ratios.std(), rel=0.05)


def test_copy_report_keeps_links_and_leaves_renders_and_spectra(tmp_path) -> None:
    out = tmp_path / "out"
    (out / "a" / "b" / "renders").mkdir(parents=True)
    for f in ("report.md", "results.csv", "summary.png", "a/b/colour-bar.png", "a/b/renders/x.exr",
              "a/b/renders/x.png", "a/b/table.csv", "a/b/densities.png"):
        (out / f).write_text(f)
    # as write_report links them: the summary, then each job's plots
    (out / "report.md").write_text("# r\n\n![summary](summary.png)\n\n## a\n\n![colour bar](a/b/colour-bar.png)\n")
    copied = commands.copy_report(out, tmp_path / "docs")
    assert sorted(p.relative_to(tmp_path / "docs").as_posix() for p in copied) == \
        ["a/b/colour-bar.png", "report.md", "results.csv", "summary.png"]


def test_render_reports_progress_and_the_renderer_s_errors(tmp_path, cornell, pbrt) -> None:
    from wavelength_pdf.evaluation import render as rendering
    from wavelength_pdf.evaluation.scene_edit import edit_scene

    scene = edit_scene(cornell, None, tmp_path / "s.pbrt", resolution=(16, 16))
    uniform = rendering.samplers(None, 380, 780)["uniform"]
    seen: list[int] = []
    r = rendering.render(scene, tmp_path / "a.exr", uniform, 256, pbrt=pbrt, on_percent=seen.append)
    assert r.image.is_file() and seen and seen[-1] == 100 and seen == sorted(seen)
    bad = tmp_path / "bad.pbrt"
    bad.write_text('WorldBegin\nShape "sphere" "float radius" [ oops ]\n')
    for progress in (None, seen.append):
        with pytest.raises(rendering.RenderError, match=r"bad\.pbrt:2"):
            rendering.render(bad, tmp_path / "b.exr", uniform, 4, pbrt=pbrt, on_percent=progress)


def test_whole_scene_keeps_the_scenes_own_lamps(tmp_path, repo, pbrt, capsys) -> None:
    """``evaluate SCENE whole-scene``: the scene copy keeps both of its lamps (their spectra as
    written), and every method gets its rows."""
    scene = repo / "scenes" / "cornell-box-two-lamps" / "scene.pbrt"
    code = main(["evaluate", str(scene), "whole-scene", "--table", str(TABLE), "-o", str(tmp_path),
                 "--spp", "4", "--truth-spp", "64", "--truth-method", "uniform", "--resolution", "12x12",
                 "--methods", "uniform", "table", "--pbrt", str(pbrt), "--nthreads", "2"])
    assert code == 0, capsys.readouterr().err
    copy = (tmp_path / "scene.pbrt").read_text()
    assert "tri-band-fluorescent.spd" in copy and "high-pressure-sodium.spd" in copy
    rows = (tmp_path / "results.csv").read_text().splitlines()
    assert len(rows) == 3 and "cornell-box-two-lamps-whole-scene" in rows[1]


def test_whole_scene_and_reflectances_bad_input_exit_2(tmp_path, repo, capsys) -> None:
    dark = tmp_path / "dark.pbrt"
    dark.write_text('WorldBegin\nShape "sphere"\n')
    assert main(["evaluate", str(dark), "whole-scene", "-o", str(tmp_path / "o")]) == 2
    assert "no emitters" in capsys.readouterr().err
    bad = tmp_path / "refl.csv"
    bad.write_text("lambda,a\n400,nan\n500,0.5\n")
    scene = repo / "scenes" / "cornell-box" / "scene.pbrt"
    assert main(["evaluate", str(scene), "cie:FL2", "--reflectances", str(bad), "-o", str(tmp_path / "o")]) == 2
    assert f"{bad}:2: reflectance 'a' is nan" in capsys.readouterr().err
