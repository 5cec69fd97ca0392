"""wavelength-pdf choose: each table's image error in a scene, predicted from three renders of
it (wavelength_pdf.evaluation.choose, design §6.8)."""
from __future__ import annotations

import numpy as np
import pytest

from repo_paths import REPO
from wavelength_pdf import stratified
from wavelength_pdf.cli import main
from wavelength_pdf.evaluation import choose
from wavelength_pdf.table import read_table

BOX = REPO / "scenes" / "cornell-box" / "scene.pbrt"  # one tri-band fluorescent lamp
TWO = REPO / "scenes" / "cornell-box-two-lamps" / "scene.pbrt"
EVALUATIONS = 40  # each polish's budget in the tests that polish


@pytest.fixture(scope="module")
def box_predictions(tmp_path_factory, pbrt):
    from wavelength_pdf.evaluation import transfer

    spd = choose.simple_tables(transfer.one_kind(BOX))["spd"]
    work = tmp_path_factory.mktemp("choose")
    return choose.predict_tables(BOX, {"copy-of-spd": spd}, 16, work, resolution=0.08, pbrt=pbrt,
                                 transfer_spp=128), work


def test_under_a_line_lamp_the_lamps_own_samplers_are_predicted_best(box_predictions):
    """Under a tri-band fluorescent lamp, sampling the lamp's spectrum (spd, xyz) leaves far
    less colour noise than uniform or visible sampling; a table equal to spd is predicted
    exactly as spd; the path noise is every candidate's."""
    preds, _ = box_predictions
    by = {p.name: p for p in preds}
    assert set(by) == {*stratified.METHODS, "copy-of-spd"}
    assert [p.wavelength for p in preds] == sorted(p.wavelength for p in preds)
    assert by["copy-of-spd"].wavelength == by["spd"].wavelength
    assert max(by["spd"].wavelength, by["xyz"].wavelength) < 0.2 * min(by["uniform"].wavelength,
                                                                        by["visible"].wavelength)
    assert len({p.path for p in preds}) == 1 and preds[0].path > 0


def test_cli_writes_the_best_table(box_predictions, tmp_path, pbrt, capsys):
    preds, work = box_predictions
    out = tmp_path / "best.csv"
    assert main(["choose", str(BOX), "--spp", "16", "--resolution-scale", "0.08", "--transfer-spp", "128",
                 "--workdir", str(work), "--pbrt", str(pbrt), "--quiet", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"best: {preds[0].name}" in text
    best = read_table(out)
    np.testing.assert_array_equal(best.pdfs, np.asarray(preds[0].table.pdfs))
    assert any("chosen by wavelength-pdf choose" in c for c in best.comments)


def test_an_emitter_of_another_kind_is_refused(tmp_path, capsys):
    """An RGB emitter beside a lamp with a spectrum: its light is not the lamp's, so the scene
    is not one lamp times a transfer; refused, naming the emitter's file and line."""
    scene = tmp_path / "mixed.pbrt"
    text = (REPO / "tests" / "data" / "scenes" / "inline.pbrt").read_text()
    scene.write_text(text + 'AttributeBegin\n  AreaLightSource "diffuse" "rgb L" [ 1 0.8 0.6 ]\n'
                            '  Shape "sphere" "float radius" [ 0.2 ]\nAttributeEnd\n')
    work = tmp_path / "work"
    assert main(["choose", str(scene), "--workdir", str(work)]) == 2
    err = capsys.readouterr().err
    assert f"mixed.pbrt:{len(text.splitlines()) + 2}:" in err and "without a lamp spectrum" in err
    assert not work.exists()


@pytest.mark.parametrize("args, message", [
    ([str(TWO)], "2 kinds of light"),
    ([str(BOX), "--spp", "48"], "not a power of two"),
    ([str(BOX), "missing.csv"], "missing.csv"),
    ([str(BOX), "--no-simple"], "nothing to compare"),
    ([str(BOX), "--resolution-scale", "2"], "resolution-scale"),
])
def test_bad_input_is_refused_before_any_render(args, message, tmp_path, capsys):
    work = tmp_path / "work"
    assert main(["choose", *args, "--workdir", str(work)]) == 2
    assert message in capsys.readouterr().err
    assert not work.exists()


def test_a_scene_without_a_film_gets_a_spectral_one(tmp_path, pbrt, capsys):
    """pbrt-v4's default film (1280 x 720) when the scene has no Film statement: the copy gets
    a spectral film of that size times the scale, before WorldBegin, and the choice runs."""
    text = (REPO / "tests" / "data" / "scenes" / "inline.pbrt").read_text()
    scene = tmp_path / "nofilm.pbrt"
    scene.write_text("".join(line for line in text.splitlines(keepends=True) if not line.startswith("Film")))
    work = tmp_path / "work"
    assert main(["choose", str(scene), "--spp", "4", "--resolution-scale", "0.02", "--transfer-spp", "16",
                 "--workdir", str(work), "--pbrt", str(pbrt), "--quiet"]) == 0
    assert "best: " in capsys.readouterr().out
    copy = (work / "scene.pbrt").read_text()
    assert copy.count("Film ") == 1 and copy.index("Film ") < copy.index("WorldBegin")
    assert '"integer xresolution" [ 26 ] "integer yresolution" [ 14 ]' in copy and '"spectral"' in copy


def test_the_polish_is_never_predicted_worse_than_the_table_it_started_from(box_predictions, pbrt):
    """``--polish`` adds the spd table and each given table polished for the box's pixels
    (design §4.6): each polish is predicted no worse than its start, since the ``pixels``
    objective is the prediction itself, and the ranking still runs best first. Below 64 spp
    each start is also polished at 64 spp and then at 16: predicted at 16 spp no worse than
    the 64-spp polish it started from. (Short polishes, ``polish_evaluations``, for the
    suite's time: the property holds for any budget.)"""
    _, work = box_predictions
    from wavelength_pdf import predict as P
    from wavelength_pdf.evaluation import transfer

    spectrum = transfer.one_kind(BOX)
    spd = choose.simple_tables(spectrum)["spd"]
    preds = choose.predict_tables(BOX, {"copy-of-spd": spd}, 16, work, resolution=0.08, pbrt=pbrt,
                                  transfer_spp=128, polish=True, polish_evaluations=EVALUATIONS)
    by = {p.name: p for p in preds}
    via = [f"polished {s} via {choose.CONTINUATION_SPP} spp" for s in ("spd", "copy-of-spd")]
    assert set(by) == {*stratified.METHODS, "copy-of-spd", "polished spd", "polished copy-of-spd", *via}
    assert [p.wavelength for p in preds] == sorted(p.wavelength for p in preds)
    for start in ("spd", "copy-of-spd"):
        assert by[f"polished {start}"].wavelength <= by[start].wavelength * (1 + 1e-9)
    tr = transfer.of_file(BOX, work, 0.08, pbrt, 128)
    first = choose.polished_tables(spectrum, tr, choose.CONTINUATION_SPP, {"spd": spd},
                                   max_evaluations=EVALUATIONS)["polished spd"]
    basis = P.hat_basis(tr.centres, transfer.LO, transfer.HI)
    assert by[via[0]].wavelength <= choose.wavelength_error(first, spectrum, basis, tr, 16) * (1 + 1e-9)
    for name in ("polished spd", "polished copy-of-spd", *via):  # four densities on the start's grid
        t = by[name].table
        np.testing.assert_array_equal(np.asarray(t.grid), np.asarray(spd.grid))
        np.testing.assert_allclose(np.trapezoid(np.asarray(t.pdfs), np.asarray(t.grid), axis=-1), 1.0, atol=1e-9)


def test_the_spread_is_measured_at_the_scenes_own_size(tmp_path, pbrt, capsys):
    """``--spread --polish`` on a tiny scene: the transfer is the scene's own film size with
    a spread per lit pixel, and the written best table is one of the candidates."""
    text = (REPO / "tests" / "data" / "scenes" / "inline.pbrt").read_text()
    scene = tmp_path / "lamp.pbrt"  # a lamp that emits over the whole range, so its spd table is healthy
    scene.write_text(text.replace("[ 400 0.0  450 1.0", "[ 380 0.3  450 1.0").replace("700 0.0 ]", "780 0.2 ]"))
    work, out = tmp_path / "work", tmp_path / "best.csv"
    assert main(["choose", str(scene), "--spp", "4", "--transfer-spp", "16", "--spread", "--polish",
                 "--polish-evaluations", str(EVALUATIONS), "--workdir", str(work), "--pbrt", str(pbrt), "--quiet", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "polished spd" in text and out.is_file()
    copy = (work / "scene.pbrt").read_text()
    assert '"integer xresolution" [ 8 ] "integer yresolution" [ 8 ]' in copy
    assert (work / "spread").is_dir()


@pytest.mark.parametrize("args, message", [
    ([str(BOX), "--spread", "--resolution-scale", "0.5"], "film size"),
    ([str(BOX), "--polish", "--pixel-sampler", "independent"], "low-discrepancy"),
    ([str(BOX), "--polish-evaluations", "10"], "give --polish too"),
])
def test_the_polish_and_the_spread_refuse_what_they_do_not_model(args, message, tmp_path, capsys):
    work = tmp_path / "work"
    assert main(["choose", *args, "--workdir", str(work)]) == 2
    assert message in capsys.readouterr().err
    assert not work.exists()


def test_the_polish_budgets_default_is_the_solvers():
    """``--help`` names the polish's default budget without importing the solvers; it is theirs."""
    from wavelength_pdf.cli import choose as cli_choose
    from wavelength_pdf.solvers import REFINE_EVALUATIONS

    assert cli_choose.REFINE_EVALUATIONS == REFINE_EVALUATIONS
