"""The wavelength-pdf command (design §7): help, bad input, writing tables, batch, show.

Most tests call ``cli.main(argv)`` in-process. The command's own logic (what is written,
when, with which header; exit statuses; resuming) is tested with a stand-in for the solver
run: the package's initialization, scored by the real ``evaluate_table``, so these tests do
not depend on how long a real optimization takes. The end-to-end tests at the bottom run the real
optimizer (and the installed console script) on a tiny problem.
"""
from __future__ import annotations

import csv
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf import cli
from wavelength_pdf.result import read_header
from wavelength_pdf.table import Table, read_table, write_table

from repo_paths import REPO  # noqa: E402
DATA = REPO / "tests" / "data"
CONSOLE = Path(sys.executable).parent / "wavelength-pdf"


# --- a stand-in optimizer ------------------------------------------------------------

def _fake_optimizer(monkeypatch, accepted: bool = True) -> list:
    """Replace the solver run by the package's initialization, scored by the real
    ``evaluate_table`` (so the record, its acceptance and its header are the real ones);
    ``accepted=False`` scores a table that drops every density below 500 nm (biased).
    Returns the list of spectra it saw."""
    from wavelength_pdf import init, optimize
    from wavelength_pdf.problem import make_problem

    calls: list = []

    def optimize_spectrum(spectrum, grid="auto", solver=None, seed=0, progress=None,
                          max_seconds=None, solver_options=None, reflectances=None):
        calls.append(spectrum.name)
        if isinstance(grid, str):  # "auto": the stand-in keeps the default 5 nm grid
            grid = np.arange(380.0, 781.0, 5.0)
        P = init.equal_mass_partition(make_problem(spectrum, grid))
        if not accepted:
            P = np.where(np.asarray(grid)[None, :] < 500.0, 0.0, P + 1e-3)
        if progress is not None:
            progress(1, 2.0)
            progress(2, 1.0)
        r = optimize.evaluate_table(spectrum, Table(grid=np.asarray(grid), pdfs=P), reflectances)
        r.solver, r.seed, r.message = solver or "stand-in", seed, "stand-in"
        return r

    monkeypatch.setattr(optimize, "optimize_spectrum", optimize_spectrum)
    return calls


# --- help ----------------------------------------------------------------------------

def test_help_lists_subcommands(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    for cmd in ("optimize", "batch", "show"):
        assert cmd in out, out


def test_every_option_has_help_text():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name, p in sub.choices.items():
        for action in p._actions:
            assert action.help, f"{name} {action.option_strings or action.dest} has no help"


def test_help_lists_the_solver_registry(capsys):
    solvers = pytest.importorskip("wavelength_pdf.solvers")
    with pytest.raises(SystemExit):
        cli.main(["optimize", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert solvers.SOLVERS, "the registry is empty"
    for name in solvers.SOLVERS:
        assert name in out, f"solver {name} missing from optimize --help"


# --- bad input: exit 2 and a message, never a traceback ------------------------------

@pytest.mark.parametrize(
    "argv, message",
    [
        (["optimize", str(DATA / "spectra" / "bad-nan.csv"), "-o", "{tmp}/t.csv"],
         f"{DATA / 'spectra' / 'bad-nan.csv'}:6: value is nan"),
        (["optimize", str(DATA / "spectra" / "missing.csv"), "-o", "{tmp}/t.csv"], "no such file"),
        (["optimize", "cie:NOPE", "-o", "{tmp}/t.csv"], "unknown CIE illuminant"),
        (["optimize", str(DATA / "scenes" / "rgb.pbrt"), "-o", "{tmp}/t.csv"], "rgb.pbrt:3:"),
        (["optimize", "cie:A", "-o", "{tmp}/t.csv", "--range", "780", "380"], "--range"),
        (["optimize", "cie:A", "-o", "{tmp}/t.csv", "--grid-step", "7"], "does not divide"),
        (["optimize", str(DATA / "scenes" / "several.pbrt"), "-o", "{tmp}/t.csv"],
         "4 emitter spectra"),
        (["show", "{tmp}/none.csv"], "no such file"),
        (["show", "{tmp}/bad.csv"], "bad.csv:3: pdf0 is negative"),
        (["batch", "{tmp}/no-folder", "-o", "{tmp}/out"], "not a folder"),
        # Directories where files are expected: named as such, not "no such file".
        (["optimize", "{tmp}/dir.spd", "-o", "{tmp}/t.csv"], "dir.spd: is a directory"),
        (["optimize", "{tmp}/dir.pbrt", "-o", "{tmp}/t.csv"], "dir.pbrt is a directory"),
        (["optimize", "{tmp}/inc.pbrt", "-o", "{tmp}/t.csv"], "inc.pbrt:2: "),
        # Objectives (design §4.6): checked before any work.
        (["optimize", "cie:A", "-o", "{tmp}/t.csv", "--objective", "pixel"], "unknown objective 'pixel'"),
        (["optimize", "cie:A", "-o", "{tmp}/t.csv", "--objective-spp", "16"], "only used with --objective stratified"),
        (["optimize", "cie:A", "-o", "{tmp}/t.csv", "--objective", "stratified", "--objective-spp", "5000"],
         "1..4096"),
        (["batch", "{tmp}", "-o", "{tmp}/out", "--objective", "j"], "unknown objective 'j'"),
        (["batch", "{tmp}", "-o", "{tmp}/out", "--reflectances", "scene"], "optimize's, for one .pbrt scene"),
        (["batch", "{tmp}", "-o", "{tmp}/out", "--reflectances", "{tmp}/none.csv"], "none.csv"),
        (["show", "{tmp}/bad.csv", "--objective", "stratified"], "--objective needs --spectrum"),
    ],
)
def test_bad_input_exits_2_with_message(tmp_path, capsys, argv, message):
    (tmp_path / "bad.csv").write_text("lambda_nm,pdf0,pdf1,pdf2,pdf3\n380,1,1,1,1\n780,-1,1,1,1\n")
    (tmp_path / "dir.spd").mkdir()
    (tmp_path / "dir.pbrt").mkdir()
    (tmp_path / "inc.pbrt").write_text('WorldBegin\nInclude "dir.pbrt"\n')
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = cli.main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("wavelength-pdf: ") and message in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "t.csv").exists()


def test_unknown_solver_is_bad_input(tmp_path, capsys):
    solvers = pytest.importorskip("wavelength_pdf.solvers")
    assert "no-such-solver" not in solvers.SOLVERS
    assert cli.main(["optimize", "cie:A", "-o", str(tmp_path / "t.csv"),
                     "--solver", "no-such-solver"]) == 2
    assert "unknown solver" in capsys.readouterr().err


def test_console_script_bad_input(tmp_path):
    """The installed command: status 2, one line naming file and line, no traceback."""
    if not CONSOLE.is_file():
        pytest.skip(f"{CONSOLE} is not installed")
    bad = DATA / "spectra" / "bad-negative.spd"
    r = subprocess.run([str(CONSOLE), "optimize", str(bad), "-o", str(tmp_path / "t.csv")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip() == f"wavelength-pdf: {bad}:2: negative value -0.5 at 450.0 nm"
    assert not (tmp_path / "t.csv").exists()


# --- optimize (command logic, stand-in optimizer) ------------------------------------

def test_optimize_writes_table_with_header(tmp_path, capsys, monkeypatch):
    calls = _fake_optimizer(monkeypatch)
    out = tmp_path / "sub" / "fl.csv"
    code = cli.main(["optimize", "cie:FL2", "-o", str(out), "--quiet", "--seed", "3"])
    assert code == 0 and calls == ["FL2"]
    t = read_table(out)
    np.testing.assert_array_equal(t.grid, np.arange(380.0, 781.0, 5.0))
    hdr = read_header(t)
    assert hdr["name"] == "FL2" and hdr["source"] == "cie:FL2" and hdr["seed"] == "3"
    for key in ("J_uniform", "J_init", "J", "J_fine", "bias_rel", "std_rel", "solver",
                "seconds", "version"):
        assert key in hdr, f"{key} missing from the header: {hdr}"
    from wavelength_pdf import evaluate_table, load_spectrum

    ev = evaluate_table(load_spectrum("cie:FL2"), t)
    assert float(hdr["J"]) == ev.J and float(hdr["J_uniform"]) == ev.J_uniform
    assert float(hdr["J_init"]) == ev.J_init and float(hdr["J_fine"]) == ev.J_fine
    assert hdr["std_rel"] == "[" + ", ".join(repr(float(v)) for v in ev.std_rel) + "]"
    assert hdr["accepted"] == "True"
    line = capsys.readouterr().out.strip()
    assert line.startswith("FL2: J ") and "accepted" in line and str(out) in line
    assert len(line.splitlines()) == 1


def test_not_accepted_is_not_written(tmp_path, capsys, monkeypatch):
    _fake_optimizer(monkeypatch, accepted=False)
    out = tmp_path / "fl.csv"
    assert cli.main(["optimize", "cie:FL2", "-o", str(out), "--quiet"]) == 1
    assert not out.exists()
    err = capsys.readouterr().err
    assert "not accepted" in err and "relative bias" in err


def test_scene_with_several_emitters_writes_one_table_each(tmp_path, monkeypatch, capsys):
    """One table per emitter, by name or by index; an emitter whose table is not accepted
    (here the stand-in's equal-mass table for the blackbody, worse than uniform) gets none,
    and the exit status says so."""
    from wavelength_pdf import evaluate_table
    from wavelength_pdf.spectra import load_spectra

    calls = _fake_optimizer(monkeypatch)
    scene = DATA / "scenes" / "several.pbrt"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        codes = [cli.main(["optimize", str(scene), "-o", f"{tmp_path}/tables/", "--quiet"]),
                 cli.main(["optimize", str(scene), "-o", f"{tmp_path}/p-{{index}}.csv",
                           "--quiet"])]
        spectra = load_spectra(str(scene))
    names = ["several-line3", "tiny", "blackbody-5000K", "stdillum-F2"]
    assert calls == names * 2 and [s.name for s in spectra] == names
    ok = []
    for i, (n, sp) in enumerate(zip(names, spectra)):
        by_name, by_index = tmp_path / "tables" / f"{n}.csv", tmp_path / f"p-{i}.csv"
        assert by_name.exists() == by_index.exists()
        if by_name.exists():
            assert read_header(read_table(by_name))["name"] == n
            assert read_header(read_table(by_index))["name"] == n
            ok.append(n)
        else:
            assert f"{n}: result not accepted" in capsys.readouterr().err
    assert "tiny" in ok and "blackbody-5000K" not in ok
    assert codes == [0 if len(ok) == 4 else 1] * 2


def test_colour_bar_and_plot_are_pngs(tmp_path, monkeypatch):
    _fake_optimizer(monkeypatch)
    cb, pl = tmp_path / "cb.png", tmp_path / "pl.png"
    assert cli.main(["optimize", "cie:FL2", "-o", str(tmp_path / "t.csv"), "--quiet",
                     "--colour-bar", str(cb), "--plot", str(pl)]) == 0
    for png in (cb, pl):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png


def test_colour_bar_rows_are_right():
    """Target row is the exact colour; the result row averages to it (unbiased table)."""
    from wavelength_pdf import init, plots
    from wavelength_pdf.problem import make_problem
    from wavelength_pdf.spectra import load_spectrum

    sp = load_spectrum("cie:FL2")
    grid = np.arange(380.0, 781.0, 5.0)
    P = init.equal_mass_partition(make_problem(sp, grid))
    labels, xyz = plots.colour_bar_rows(sp, Table(grid, P), n_u=4096)
    assert labels == ["uniform", "initialization", "result", "target"]
    np.testing.assert_allclose(xyz[-1], np.broadcast_to(xyz[-1, 0], xyz[-1].shape))
    assert xyz[-1, 0, 1] == pytest.approx(1.0, rel=1e-12), "target scaled to Y = 1"
    # Midpoint rule over u: the mean of C(u) is the target to within the rule's error.
    np.testing.assert_allclose(xyz[2].mean(axis=0), xyz[-1, 0], rtol=2e-3)
    np.testing.assert_allclose(xyz[0].mean(axis=0), xyz[-1, 0], rtol=2e-3)


# --- batch ---------------------------------------------------------------------------

def _batch_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("tiny.spd", "tiny-lspdd.csv", "bad-nan.csv"):
        (folder / name).write_bytes((DATA / "spectra" / name).read_bytes())
    (folder / "notes.txt").write_text("not a spectrum")
    return folder


def test_batch_tables_summary_and_resume(tmp_path, monkeypatch, capsys):
    calls = _fake_optimizer(monkeypatch)
    folder, out = _batch_folder(tmp_path), tmp_path / "out"
    code = cli.main(["batch", str(folder), "-o", str(out), "--quiet"])
    assert code == 2, "one input is malformed"
    assert sorted(calls) == ["Testbrand Tiny Triband (CFL)", "tiny"]
    with open(out / "summary.csv") as fh:
        rows = {Path(r["input"]).name: r for r in csv.DictReader(fh)}
    assert set(rows) == {"tiny.spd", "tiny-lspdd.csv", "bad-nan.csv"}
    assert rows["bad-nan.csv"]["status"] == "error" and ":6:" in rows["bad-nan.csv"]["message"]
    for name in ("tiny.spd", "tiny-lspdd.csv"):
        r = rows[name]
        assert r["status"] == "written" and r["accepted"] == "True"
        t = read_table(r["table"])
        assert read_header(t)["J"] == r["J"]
    assert sorted(p.name for p in out.iterdir()) == ["summary.csv", "tiny-lspdd.csv", "tiny.csv"]

    # Second run: nothing to do; the summary is rebuilt from the tables' headers.
    calls.clear()
    cli.main(["batch", str(folder), "-o", str(out), "--quiet"])
    assert calls == []
    with open(out / "summary.csv") as fh:
        again = {Path(r["input"]).name: r for r in csv.DictReader(fh)}
    assert again["tiny.spd"]["status"] == "kept"
    assert again["tiny.spd"]["J"] == rows["tiny.spd"]["J"]

    # An input newer than its table is redone.
    later = (out / "tiny.csv").stat().st_mtime + 10
    os.utime(folder / "tiny.spd", (later, later))
    cli.main(["batch", str(folder), "-o", str(out), "--quiet"])
    assert calls == ["tiny"]


def test_batch_for_surface_colours_redoes_white_tables(tmp_path, monkeypatch, capsys):
    """--reflectances colorchecker: every table is made for the 24 patches (design §4.5) and
    says so; a kept white table is redone, a kept ColorChecker table is kept."""
    calls = _fake_optimizer(monkeypatch)
    folder, out = tmp_path / "in", tmp_path / "out"
    folder.mkdir()
    (folder / "tiny.spd").write_bytes((DATA / "spectra" / "tiny.spd").read_bytes())
    assert cli.main(["batch", str(folder), "-o", str(out), "--quiet"]) == 0
    assert "reflectances" not in read_header(read_table(out / "tiny.csv"))["source"]
    for expected in (["tiny"], []):
        calls.clear()
        assert cli.main(["batch", str(folder), "-o", str(out), "--quiet", "--reflectances", "colorchecker"]) == 0
        assert calls == expected
        assert read_header(read_table(out / "tiny.csv"))["source"].endswith(
            "; reflectances: colorchecker (24 colours, colour.SDS_COLOURCHECKERS['ColorChecker N Ohta'])")
    calls.clear()
    cli.main(["batch", str(folder), "-o", str(out), "--quiet"])  # back to white: redone
    assert calls == ["tiny"]
    # A reflectance file: its tables are kept until the file changes.
    colours = tmp_path / "colours.csv"
    colours.write_text("lambda_nm,grey,red\n380,0.5,0.1\n780,0.5,0.8\n")
    for touch, expected in ((False, ["tiny"]), (False, []), (True, ["tiny"])):
        if touch:
            later = (out / "tiny.csv").stat().st_mtime + 10
            os.utime(colours, (later, later))
        calls.clear()
        assert cli.main(["batch", str(folder), "-o", str(out), "--quiet", "--reflectances", str(colours)]) == 0
        assert calls == expected


def test_batch_parallel_workers_report_errors(tmp_path, capsys):
    """--jobs 2 runs items in spawned worker processes; their rows reach summary.csv."""
    folder, out = tmp_path / "in", tmp_path / "out"
    folder.mkdir()
    for name in ("bad-nan.csv", "bad-negative.spd", "bad-outside.spd"):
        (folder / name).write_bytes((DATA / "spectra" / name).read_bytes())
    assert cli.main(["batch", str(folder), "-o", str(out), "--jobs", "2", "--quiet"]) == 2
    with open(out / "summary.csv") as fh:
        rows = {Path(r["input"]).name: r for r in csv.DictReader(fh)}
    assert {n: r["status"] for n, r in rows.items()} == {
        "bad-nan.csv": "error", "bad-negative.spd": "error", "bad-outside.spd": "error"}
    assert "bad-negative.spd:2: negative value" in rows["bad-negative.spd"]["message"]
    assert sorted(p.name for p in out.iterdir()) == ["summary.csv"], "no table for bad input"
    assert capsys.readouterr().err.count("error") == 3


# --- show ----------------------------------------------------------------------------

def test_show_prints_grid_normalization_and_J(tmp_path, capsys):
    from wavelength_pdf import objective
    from wavelength_pdf.problem import make_problem
    from wavelength_pdf.spectra import load_spectrum

    grid = np.linspace(380.0, 780.0, 41)
    P = np.ones((4, 41))
    P[3, :20] = 0.0
    path = tmp_path / "t.csv"
    write_table(path, Table(grid, P / np.array([[400.0], [400.0], [400.0], [200.0]]),
                            ["name: flat"]))
    assert cli.main(["show", str(path), "--spectrum", "cie:D65"]) == 0
    out = capsys.readouterr().out
    assert "41 nodes, 380-780 nm, step 10 nm" in out
    assert out.count("integral 1,") == 4
    # pdf3 is 0 up to 570 nm, a ramp to 580 nm, then flat: 1 / 205 after renormalizing.
    assert "pdf3: integral 1, max 0.00487805 /nm at 580 nm, non-zero 580-780 nm" in out
    assert "# name: flat" in out
    j = objective.J(make_problem(load_spectrum("cie:D65"), grid), read_table(path).pdfs)
    assert f"D65: J {j:.6g}" in out, out
    # By the pixel's objective (design §4.6), named.
    from wavelength_pdf.problem import with_objective

    assert cli.main(["show", str(path), "--spectrum", "cie:D65", "--objective", "stratified",
                     "--objective-spp", "8"]) == 0
    out = capsys.readouterr().out
    j8 = objective.J(with_objective(make_problem(load_spectrum("cie:D65"), grid), "stratified", 8),
                     read_table(path).pdfs)
    assert f"D65: J [stratified, spp 8] {j8:.6g}" in out, out


# --- end to end with the real optimizer ----------------------------------------------

def test_optimize_for_a_pixel_end_to_end(tmp_path):
    """--objective stratified: the header names it and states the objective's value of the
    table written, no worse than J's own table by that objective."""
    from wavelength_pdf import objective
    from wavelength_pdf.problem import make_problem, with_objective
    from wavelength_pdf.spectra import load_spectrum

    out, plain = tmp_path / "t.csv", tmp_path / "j.csv"
    base = ["--grid-step", "20", "--max-evals", "60", "--quiet"]
    assert cli.main(["optimize", "cie:FL2", "-o", str(plain), *base]) == 0
    assert cli.main(["optimize", "cie:FL2", "-o", str(out), "--objective", "stratified",
                     "--objective-spp", "16", *base]) == 0
    t, hdr = read_table(out), read_header(read_table(out))
    assert hdr["objective"] == "stratified, spp 16" and read_header(read_table(plain))["objective"] == "J"
    problem = with_objective(make_problem(load_spectrum("cie:FL2"), t.grid), "stratified", 16)
    assert objective.J(problem, t.pdfs) == pytest.approx(float(hdr["J"]), rel=1e-9)
    assert float(hdr["J"]) <= objective.J(problem, read_table(plain).pdfs) * (1 + 1e-9)
    assert float(hdr["J"]) < float(hdr["J_uniform"])


def test_optimize_end_to_end(tmp_path):
    """The real optimizer on a small problem (60 evaluations): a valid table, no worse than
    the initialization, whose header states the J of the table written."""
    out = tmp_path / "t.csv"
    code = cli.main(["optimize", "cie:D65", "-o", str(out), "--grid-step", "20",
                     "--max-evals", "60", "--quiet"])
    assert code == 0
    t = read_table(out)
    assert t.grid.size == 21
    hdr = read_header(t)
    assert hdr["name"] == "D65" and hdr["accepted"] == "True"
    assert float(hdr["J"]) <= float(hdr["J_init"]) * (1 + 1e-12)
    from wavelength_pdf import objective
    from wavelength_pdf.problem import make_problem
    from wavelength_pdf.spectra import load_spectrum

    problem = make_problem(load_spectrum("cie:D65"), t.grid)
    assert objective.J(problem, t.pdfs) == pytest.approx(float(hdr["J"]), rel=1e-9), \
        "the header's J is the J of the written table"
