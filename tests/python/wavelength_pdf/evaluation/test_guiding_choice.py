"""wavelength-pdf choose-guiding: each guiding mixture's table, emission's or an optimized one, by
the predicted image error over the pixels it lights (evaluation.guiding_choice, design §1.8, §6.8).

On the two-lamp box (a tri-band fluorescent and a sodium lamp, so guiding builds several
tables) at a small size:
- the renderer's spectra folder carries what the prediction needs, and agrees with a render at
  the same settings (tile map, emission tables as sampled);
- ``with_defensive`` mixes a table as the renderer does (the render's table-K.csv);
- the choice is each table's least prediction, uniform sampling (a poor table for line
  lamps) is never chosen, the output holds exactly the chosen files byte for byte, and the
  renderer takes them (its clusters.csv names them) and keeps emission tables elsewhere;
- bad inputs are refused before any render.
"""
from __future__ import annotations

import csv
import re
import subprocess

import numpy as np
import pytest

from repo_paths import REPO
from wavelength_pdf import stratified
from wavelength_pdf.cli import main
from wavelength_pdf.evaluation import guiding_choice as G
from wavelength_pdf.evaluation import transfer
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.spectra import read_spd
from wavelength_pdf.table import read_table, write_table

TWO = REPO / "scenes" / "cornell-box-two-lamps" / "scene.pbrt"
SETTINGS = ("--quiet", "--spp", "16", "--wavelength-guiding", "--guiding-tile", "3",
            "--guiding-prepass-share", "0.25")


def pdf_at(table, lam):
    return np.stack([np.interp(lam, table.grid, p, left=0.0, right=0.0) for p in np.asarray(table.pdfs)])


@pytest.fixture(scope="module")
def setup(tmp_path_factory, pbrt):
    """The small scene, its spectra folder, two candidate folders and the choice."""
    tmp = tmp_path_factory.mktemp("guiding-choice")
    scene = edit_scene(TWO, None, tmp / "two.pbrt", resolution=(24, 18), maxdepth=3)
    spectra = tmp / "spectra"
    r = subprocess.run([str(pbrt), *SETTINGS, "--wavelength-guiding-spectra", str(spectra), str(scene)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    mixtures = G.read_clusters(spectra / "clusters.txt")
    assert len(mixtures) >= 2, "the two-lamp box should need several tables"
    folders = {"uniform": tmp / "uniform", "xyz": tmp / "xyz"}
    for f in folders.values():
        f.mkdir()
    for mix in mixtures.values():
        m = read_spd(spectra / f"{mix}.spd", transfer.LO, transfer.HI)
        write_table(folders["uniform"] / f"{mix}.csv", stratified.uniform_table(transfer.LO, transfer.HI))
        write_table(folders["xyz"] / f"{mix}.csv", stratified.stratified_table(m, "xyz", transfer.LO, transfer.HI))
    out = tmp / "chosen"
    choices = G.choose_guiding_tables(scene, spectra, folders, 16, out, tmp / "work", resolution=0.5, pbrt=pbrt,
                                      transfer_spp=128)
    return scene, spectra, folders, out, choices, tmp


def test_the_spectra_folder_agrees_with_a_render(setup, pbrt):
    """tiles.txt is the render's tiles.csv and table-K.txt its table-K.csv (the same pre-pass);
    defensive.txt is a density of the scene's emission with the default share 0.05."""
    scene, spectra, _, _, _, tmp = setup
    out = tmp / "render.exr"
    r = subprocess.run([str(pbrt), *SETTINGS, "--outfile", str(out), str(scene)], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    folder = out.with_suffix(".guiding")
    assert (spectra / "tiles.txt").read_text() == (folder / "tiles.csv").read_text()
    for k in G.read_clusters(spectra / "clusters.txt"):
        assert (spectra / f"table-{k}.txt").read_text() == (folder / f"table-{k}.csv").read_text()
    lam, phi, S = G.read_defensive(spectra / "defensive.txt")
    assert S == pytest.approx(0.05) and np.all(phi >= 0)
    assert np.trapezoid(phi, lam) == pytest.approx(1.0, rel=1e-9)
    tiles = G.read_tiles(spectra / "tiles.txt")
    assert tiles.tile == 3 and tiles.bounds == (0, 0, 24, 18) and tiles.index.shape == (6, 8)


def test_kinds_light_the_scene_between_them(setup, pbrt):
    """kinds.txt names each kind's spectrum and lights (the box's two lamps), and the copies lit
    by one kind each add up to the copy lit by all (the same paths, split by light), while each
    kind's copy is dark where only the other kind's lamp shines."""
    scene, spectra, _, _, _, tmp = setup
    kinds, lights = G.read_kinds(spectra / "kinds.txt")
    assert len(kinds) == 2 and all(len(ls) == 1 for ls in lights)
    assert {line for ls in lights for _, line in ls} == {
        n for n, text in enumerate(scene.read_text().splitlines(), start=1) if "AreaLightSource" in text}
    for k in kinds:
        assert np.trapezoid(k.values, k.wavelengths) == pytest.approx(1.0, rel=1e-6)
    whole = transfer.of_file(scene, tmp / "work", 0.5, pbrt, 128)
    T = transfer.kind_transfers(scene, tmp / "work", lights, whole, 0.5, pbrt, 128)
    assert T.shape == (2,) + whole.t.shape
    lum = whole.t.sum(axis=1)
    np.testing.assert_allclose(T.sum(axis=0).sum(axis=1), lum, rtol=0.35, atol=0.02 * lum.max())
    assert abs(T.sum() / whole.t.sum() - 1) < 0.05
    # each kind lights a part of the box the other does not dominate
    share = T.sum(axis=2) / np.maximum(T.sum(axis=(0, 2)), 1e-30)
    assert share[0].max() > 0.8 and share[1].max() > 0.8


def test_a_pixel_lit_by_one_kind_is_predicted_as_under_that_lamp(setup, pbrt):
    """The per-kind prediction with the other kind's transfer zero is the one-lamp prediction
    (the stacked bases' extra functions add nothing), and two kinds along the same paths are
    predicted worse than the one lamp whose spectrum is their sum: each sample carries one
    kind's light (``predict.kinds_spread``), whose change from sample to sample the pixel's
    stratification does not cancel."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.colorimetry import cmfs
    from wavelength_pdf.evaluation.choose import wavelength_error
    from wavelength_pdf.spectra import Spectrum

    scene, spectra, _, _, _, tmp = setup
    kinds, _ = G.read_kinds(spectra / "kinds.txt")
    whole = transfer.of_file(scene, tmp / "work", 0.5, pbrt, 128)
    basis = P.hat_basis(whole.centres, transfer.LO, transfer.HI)
    table = read_table(spectra / "table-0.txt")
    alone = np.stack([whole.t, np.zeros_like(whole.t)])
    one = wavelength_error(table, kinds[0], basis, whole, 16)
    assert wavelength_error(table, kinds, basis, whole, 16, kinds=alone) == pytest.approx(one, rel=1e-9)
    # Both kinds along the same paths, each at half: the one lamp whose spectrum is their sum,
    # each kind scaled to the white surface's Y = 1 as the prediction scales every lamp.
    lam = np.unique(np.concatenate([k.wavelengths for k in kinds]))
    cwl, cval = cmfs()
    ybar = np.interp(lam, cwl, cval[:, 1], left=0.0, right=0.0)
    parts = [np.interp(lam, k.wavelengths, k.values, left=0.0, right=0.0) for k in kinds]
    summed = Spectrum("sum", "test", lam, sum(e / np.trapezoid(e * ybar, lam) for e in parts))
    halves = np.stack([0.5 * whole.t, 0.5 * whole.t])
    both = wavelength_error(table, kinds, basis, whole, 16, kinds=halves)
    assert both > 2 * wavelength_error(table, summed, basis, whole, 16)  # 4.4 x here
    with pytest.raises(ValueError, match="kinds"):
        wavelength_error(table, kinds, basis, whole, 16)


def test_defensive_mixing_is_the_renderers(setup, pbrt):
    """A render with a folder of tables samples each as with_defensive makes it."""
    scene, spectra, folders, _, _, tmp = setup
    out = tmp / "xyz.exr"
    r = subprocess.run([str(pbrt), *SETTINGS, "--wavelength-guiding-tables", str(folders["xyz"]),
                        "--outfile", str(out), str(scene)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    lam, phi, S = G.read_defensive(spectra / "defensive.txt")
    x = np.linspace(360, 830, 4701)
    for k, mix in G.read_clusters(spectra / "clusters.txt").items():
        ours = G.with_defensive(read_table(folders["xyz"] / f"{mix}.csv"), lam, phi, S)
        theirs = read_table(out.with_suffix(".guiding") / f"table-{k}.csv")
        np.testing.assert_allclose(pdf_at(ours, x), pdf_at(theirs, x), rtol=1e-9, atol=1e-12)


def test_each_table_gets_its_least_prediction(setup):
    _, spectra, folders, out, choices, _ = setup
    mixtures = G.read_clusters(spectra / "clusters.txt")
    assert [c.table for c in choices] == sorted(mixtures)
    for c in choices:
        assert set(c.predicted) == {G.EMISSION, *folders}
        assert all(v > 0 and np.isfinite(v) for v in c.predicted.values())
        best = min((n for n in c.predicted if n != G.EMISSION), key=c.predicted.get)
        wins = c.predicted[best] < 0.9 * c.predicted[G.EMISSION]  # the default margin, 0.1
        assert c.chosen == (best if wins else G.EMISSION), c
        # four equal-width bands cannot follow a fluorescent's or sodium lamp's lines
        assert c.chosen != "uniform" and c.predicted["uniform"] > c.predicted[G.EMISSION]
    assert sum(c.pixels for c in choices) > 0
    kept = {f"{c.mixture}.csv": c.chosen for c in choices if c.chosen != G.EMISSION}
    assert {p.name for p in out.iterdir()} == {G.CHOICE, *kept}
    for name, chosen in kept.items():
        assert (out / name).read_bytes() == (folders[chosen] / name).read_bytes()
    with open(out / G.CHOICE, newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert [(int(r["table"]), r["chosen"]) for r in rows] == [(c.table, c.chosen) for c in choices]


def test_the_margin_decides_between_emission_and_the_best_candidate(setup, pbrt, tmp_path):
    """The default margin (0.1): each table's least prediction where it is below 0.9 times the
    emission table's, else the emission table; a margin near 1: every table keeps its emission
    table, and the folder holds choice.csv alone. The predictions do not depend on the margin.
    (The setup's choice stands for the default margin: one more prediction, for the suite's time.)"""
    scene, spectra, folders, _, choices, tmp = setup
    assert len({c.chosen for c in choices}) > 1  # both sides of the rule occur
    for c in choices:
        least = min(c.predicted, key=lambda n: (c.predicted[n], n != G.EMISSION))
        assert c.chosen == (least if c.predicted[least] < 0.9 * c.predicted[G.EMISSION] else G.EMISSION)
    out = tmp_path / "margin"
    again = G.choose_guiding_tables(scene, spectra, folders, 16, out, tmp / "work", margin=0.999,
                                    resolution=0.5, pbrt=pbrt, transfer_spp=128)
    assert [c.predicted for c in again] == [c.predicted for c in choices]
    assert all(c.chosen == G.EMISSION for c in again)
    assert [p.name for p in out.iterdir()] == [G.CHOICE]
    with pytest.raises(ValueError, match="margin"):
        G.choose_guiding_tables(scene, spectra, folders, 16, tmp_path / "m", tmp / "work", margin=1.0)


def test_the_renderer_takes_the_choice(setup, pbrt, tmp_path):
    """The output folder's contract with the renderer: where a candidate is chosen, the render's
    table comes from the folder; elsewhere it is the emission (stratified) table. (Choices
    written directly, table 0 given the xyz candidate, so that the check does not depend on
    what the prediction chose.)"""
    scene, spectra, folders, _, choices, tmp = setup
    forced = [G.MixtureChoice(c.table, c.mixture, c.pixels, c.predicted, "xyz" if c.table == 0 else G.EMISSION)
              for c in choices]
    out = tmp_path / "forced"
    G.write_choice(out, forced, {0: folders["xyz"] / f"{forced[0].mixture}.csv"})
    image = tmp_path / "chosen.exr"
    r = subprocess.run([str(pbrt), *SETTINGS, "--wavelength-guiding-tables", str(out), "--outfile", str(image),
                        str(scene)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    with open(image.with_suffix(".guiding") / "clusters.csv", newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    for c in forced:
        source = rows[c.table]["source"]
        assert (source == str(out / f"{c.mixture}.csv")) == (c.chosen != G.EMISSION), (c, source)
        assert (source == "stratified") == (c.chosen == G.EMISSION), (c, source)


def test_cli_prints_and_writes_the_choice(setup, pbrt, capsys):
    scene, spectra, folders, _, choices, tmp = setup
    out = tmp / "cli"
    assert main(["choose-guiding", str(scene), str(spectra), *(f"{n}={f}" for n, f in folders.items()),
                 "-o", str(out), "--spp", "16", "--resolution-scale", "0.5", "--transfer-spp", "128",
                 "--workdir", str(tmp / "work"), "--pbrt", str(pbrt), "--quiet"]) == 0
    text = capsys.readouterr().out
    for c in choices:  # one line per table: its index, pixels, predictions and choice
        assert re.search(rf"^ +{c.table} +{c.pixels} .* {re.escape(c.chosen)}$", text, re.M), text
    assert (out / G.CHOICE).read_text() == (setup[3] / G.CHOICE).read_text()


def test_bad_inputs_are_refused_before_any_render(setup, tmp_path, capsys):
    scene, spectra, folders, _, _, _ = setup
    work = tmp_path / "work"
    bare = tmp_path / "bare"
    bare.mkdir()
    with pytest.raises(ValueError, match="no clusters.txt"):
        G.choose_guiding_tables(scene, bare, folders, 16, tmp_path / "o1", work)
    for name in ("clusters.txt", "defensive.txt"):
        (bare / name).write_text((spectra / name).read_text())
    with pytest.raises(ValueError, match="no tiles.txt"):
        G.choose_guiding_tables(scene, bare, folders, 16, tmp_path / "o1", work)
    with pytest.raises(ValueError, match="no such folder"):
        G.choose_guiding_tables(scene, spectra, {"gone": tmp_path / "gone"}, 16, tmp_path / "o2", work)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ValueError, match="holds a table of these mixtures"):
        G.choose_guiding_tables(scene, spectra, {"empty": empty}, 16, tmp_path / "o3", work)
    other = tmp_path / "other"
    other.mkdir()
    (other / "keep.txt").write_text("a user's file")
    with pytest.raises(ValueError, match="not an earlier choice"):
        G.choose_guiding_tables(scene, spectra, folders, 16, other, work)
    assert (other / "keep.txt").read_text() == "a user's file"
    with pytest.raises(ValueError, match="power of two"):
        G.choose_guiding_tables(scene, spectra, folders, 24, tmp_path / "o4", work)
    assert not work.exists()  # nothing rendered
    bad = tmp_path / "tiles.txt"
    bad.write_text((spectra / "tiles.txt").read_text() + "1,x\n")
    with pytest.raises(ValueError, match=r"tiles.txt:\d+: not a row"):
        G.read_tiles(bad)
    assert main(["choose-guiding", str(scene), str(bare), str(folders["xyz"]), "-o", str(tmp_path / "o5")]) == 2
    assert "no tiles.txt" in capsys.readouterr().err
    assert main(["choose-guiding", str(scene), str(spectra), "-o", str(tmp_path / "o6")]) == 2
    assert "nothing to choose from" in capsys.readouterr().err
    assert main(["choose-guiding", str(scene), str(spectra), "--polish", "--pixel-sampler", "independent",
                 "-o", str(tmp_path / "o7")]) == 2
    assert "low-discrepancy" in capsys.readouterr().err
    assert main(["choose-guiding", str(scene), str(spectra), str(folders["xyz"]), "--polish-evaluations", "10",
                 "-o", str(tmp_path / "o8")]) == 2
    assert "give --polish too" in capsys.readouterr().err
    assert not work.exists() and not any((tmp_path / o).exists() for o in ("o6", "o7", "o8"))


def test_the_polish_adds_tables_no_worse_than_their_starts(setup, pbrt, tmp_path):
    """choose-guiding --polish: each table's emission table (and each folder's, none here: the
    polish needs no optimizer run), polished for its pixels and named "polished NAME", joins the
    candidates; a chosen polished table is written as polished and, read back and mixed as the
    renderer mixes it, is what was predicted. A polish is no worse than its start by the
    prediction (each pixel lit by every kind along its own paths), keeps its start's grid and is
    a density. (Two guiding tables, and short polishes, for the suite's time.)"""
    from wavelength_pdf import predict as P
    from wavelength_pdf.evaluation.choose import polished_tables, wavelength_error

    scene, _, folders, _, _, tmp = setup
    spectra = tmp_path / "spectra"
    r = subprocess.run([str(pbrt), *SETTINGS, "--guiding-tables", "2", "--wavelength-guiding-spectra", str(spectra),
                        str(scene)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    out = tmp_path / "polished"
    choices = G.choose_guiding_tables(scene, spectra, {}, 16, out, tmp / "work", margin=0.0, resolution=0.5,
                                      pbrt=pbrt, transfer_spp=128, polish=True, polish_evaluations=40)
    assert len(choices) == 2
    tr = transfer.of_file(scene, tmp / "work", 0.5, pbrt, 128)  # the choice's renders, kept
    basis = P.hat_basis(tr.centres, transfer.LO, transfer.HI)
    of_pixel = G.read_tiles(spectra / "tiles.txt").table_of(tr.mask.shape)[tr.mask]
    lam, phi, S = G.read_defensive(spectra / "defensive.txt")
    kind_spectra, kind_lights = G.read_kinds(spectra / "kinds.txt")
    kinds = transfer.kind_transfers(scene, tmp / "work", kind_lights, tr, 0.5, pbrt, 128)
    for c in choices:
        assert set(c.predicted) == {G.EMISSION, "polished emission"}, c
        assert c.chosen == min(c.predicted, key=lambda n: (c.predicted[n], n != G.EMISSION))
        if c.chosen != G.EMISSION:
            mixed = G.with_defensive(read_table(out / f"{c.mixture}.csv"), lam, phi, S)
            again = wavelength_error(mixed, kind_spectra, basis, tr, 16, "sobol",
                                     of_pixel == c.table if c.pixels else slice(None), kinds)
            assert again == pytest.approx(c.predicted[c.chosen], rel=1e-6)
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [G.CHOICE, *(f"{c.mixture}.csv" for c in choices if c.chosen != G.EMISSION)])
    c = max(choices, key=lambda c: c.pixels)
    sel = of_pixel == c.table
    mixture = read_spd(spectra / f"{c.mixture}.spd", transfer.LO, transfer.HI)
    start = G.with_defensive(stratified.stratified_table(mixture, "xyz", transfer.LO, transfer.HI), lam, phi, S)
    polished = polished_tables(kind_spectra, tr, 16, {"xyz": start}, pixels=sel, kinds=kinds,
                               max_evaluations=40)["polished xyz"]
    np.testing.assert_array_equal(polished.grid, start.grid)
    np.testing.assert_allclose(np.trapezoid(np.asarray(polished.pdfs), polished.grid, axis=1), 1.0, rtol=1e-9)
    # the search's objective is the prediction up to its quadrature (test_objective_pixels.py)
    assert (wavelength_error(polished, kind_spectra, basis, tr, 16, "sobol", sel, kinds)
            <= wavelength_error(start, kind_spectra, basis, tr, 16, "sobol", sel, kinds) * (1 + 2e-3))
    with pytest.raises(ValueError, match="low-discrepancy"):
        G.choose_guiding_tables(scene, spectra, folders, 16, tmp_path / "o", tmp / "work", polish=True,
                                pixel_sampler="independent")
    with pytest.raises(ValueError, match="polished NAME"):
        G.choose_guiding_tables(scene, spectra, {"polished xyz": folders["xyz"]}, 16, tmp_path / "o", tmp / "work",
                                polish=True)
    with pytest.raises(ValueError, match="nothing to choose"):
        G.choose_guiding_tables(scene, spectra, {}, 16, tmp_path / "o", tmp / "work")
