"""The reflectance-aware objective (design §3.4, §4.5): J as the weighted mean of each surface
colour's J, the health rules for every colour, and the reflectance sets and their bad input."""
from __future__ import annotations

import math
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

from wavelength_pdf import cli, colorimetry, health, init, objective, uniform
from wavelength_pdf.problem import make_problem
from wavelength_pdf.reflectances import (ReflectanceSet, colorchecker, load_reflectances,
                                         read_reflectances)
from wavelength_pdf.result import read_header
from wavelength_pdf.spectra import SpectrumError, load_spectrum
from wavelength_pdf.table import read_table

GRID = np.arange(380.0, 781.0, 20.0)


def refl_set(*rows, wl=(380.0, 480.0, 580.0, 680.0, 780.0)) -> ReflectanceSet:
    vals = np.asarray(rows, dtype=np.float64)
    k = vals.shape[0]
    return ReflectanceSet("test", "test", np.asarray(wl), vals, tuple(f"r{i}" for i in range(k)),
                          np.full(k, 1.0 / k))


RED = (0.05, 0.05, 0.1, 0.8, 0.9)
BLUE = (0.6, 0.5, 0.1, 0.05, 0.05)


@pytest.fixture(scope="module")
def lamp():
    return load_spectrum("cie:FL2")


@pytest.fixture(scope="module")
def table(lamp):
    return init.equal_mass_partition(make_problem(lamp, GRID))


# Every problem below has two colours (one compiled shape class: the tests stay fast).

def test_a_white_surface_is_the_plain_objective(lamp, table):
    """R = 1 everywhere: the same J, uniform J, health as design §4.1's objective."""
    plain = make_problem(lamp, GRID)
    white = make_problem(lamp, GRID, refl_set((1, 1, 1, 1, 1), (1, 1, 1, 1, 1)))
    assert white.batched and not plain.batched
    assert objective.J(white, table) == pytest.approx(objective.J(plain, table), rel=1e-12)
    assert uniform.uniform_J(white) == pytest.approx(uniform.uniform_J(plain), rel=1e-12)
    std = health.health(white, table).std
    assert std.shape == (2, 3)
    np.testing.assert_allclose(std, [health.health(plain, table).std] * 2, rtol=1e-10)


def test_J_is_the_mean_of_each_colours_J(lamp, table):
    both = make_problem(lamp, GRID, refl_set(RED, BLUE))
    red = make_problem(lamp, GRID, refl_set(RED, RED))
    blue = make_problem(lamp, GRID, refl_set(BLUE, BLUE))
    J_red, J_blue = objective.J(red, table), objective.J(blue, table)
    assert J_red != pytest.approx(J_blue, rel=1e-3)  # the colours do differ
    assert objective.J(both, table) == pytest.approx(0.5 * (J_red + J_blue), rel=1e-12)
    assert uniform.uniform_J(both) == pytest.approx(
        0.5 * (uniform.uniform_J(red) + uniform.uniform_J(blue)), rel=1e-12)


def test_each_colour_is_its_own_exact_colour_relative_to_the_white(lamp, table):
    """Target: the exact integral of I R cmf, in the scale where the white surface has Y = 1;
    the estimator's mean is that target (unbiased) for every colour."""
    p = make_problem(lamp, GRID, refl_set(RED, BLUE))
    white = make_problem(lamp, GRID)
    lam = np.linspace(380.0, 780.0, 400001)
    f = lamp(lam) * white.scale
    cmf = np.stack([np.interp(lam, white.nodes[:white.n_nodes], white.cmf[:white.n_nodes, i])
                    for i in range(3)], axis=1)
    for k, r in enumerate((RED, BLUE)):
        R = np.interp(lam, [380, 480, 580, 680, 780], r)
        c = np.trapezoid((f * R)[:, None] * cmf, lam, axis=0)
        np.testing.assert_allclose(p.c[k], c, rtol=2e-3)
        assert 0 < p.c[k][1] < 1
        np.testing.assert_allclose(p.lab_c[k], colorimetry.xyz_to_lab(p.c[k]), rtol=1e-12)
    h = health.health(p, table)
    assert h.bias_xyz.shape == (2, 3) and h.bias <= 1e-9


def test_gradient_matches_finite_differences(lamp, table):
    p = make_problem(lamp, GRID, refl_set(RED, BLUE))
    vg = objective.value_and_grad(p)
    P = np.asarray(table) + 0.2 * np.random.default_rng(1).random(np.shape(table)) * np.max(table)
    J, g = vg(P)
    g = np.asarray(g)
    assert np.all(np.isfinite(g))
    d = np.random.default_rng(2).normal(size=P.shape) * P
    h = 1e-6
    fd = (float(vg(P + h * d)[0]) - float(vg(P - h * d)[0])) / (2 * h)
    assert abs(fd - np.sum(g * d)) <= 1e-5 * max(abs(fd), 1e-3)


def test_health_holds_for_every_colour(lamp, table):
    """A table without support above 600 nm is biased for the red surface, and the bias
    and the rejection say so even though the blue surface hardly notices."""
    P = np.where(GRID[None, :] > 600.0, 0.0, np.asarray(table) + 1e-3)
    wl = (380.0, 480.0, 590.0, 600.0, 780.0)
    p = make_problem(lamp, GRID, refl_set((0.6, 0.5, 0.1, 0.0, 0.0), RED, wl=wl))
    h = health.health(p, P)
    assert np.max(np.abs(h.bias_xyz[1])) > 1e-2 and np.max(np.abs(h.bias_xyz[0])) < 1e-9
    assert h.bias == pytest.approx(np.max(np.abs(h.bias_xyz)))
    assert "relative bias" in health.rejection(h)
    # A colour whose std is worse than the initialization's is named.
    std = np.full((2, 3), 0.1)
    ref = health.Health(bias=0.0, bias_xyz=np.zeros((2, 3)), std=std, missing_mass=np.zeros((2, 3)))
    worse = health.Health(bias=0.0, bias_xyz=np.zeros((2, 3)), std=std * [[1, 1, 1], [1, 2, 1]],
                          missing_mass=np.zeros((2, 3)))
    assert health.rejection(ref, ref) == ""
    assert health.rejection(worse, ref) == ("std/c worse than the initialization's in channel(s) Y "
                                            "of surface colour #1")


def test_colorchecker_has_24_reflectances():
    cc = colorchecker()
    assert len(cc) == 24 and cc.values.shape == (24, cc.wavelengths.size)
    assert np.all((cc.values >= 0) & (cc.values <= 1))
    assert math.isclose(float(np.sum(cc.weights)), 1.0)
    assert load_reflectances("colorchecker").labels == cc.labels


def test_reading_a_reflectance_file_round_trips(tmp_path):
    f = tmp_path / "two.csv"
    f.write_text("# two surfaces\nlambda_nm,red,blue\n" +
                 "".join(f"{w},{r},{b}\n" for w, r, b in zip([380, 480, 580, 680, 780], RED, BLUE)))
    s = read_reflectances(f)
    assert s.labels == ("red", "blue") and s.name == "two"
    np.testing.assert_array_equal(s.values, [RED, BLUE])
    np.testing.assert_array_equal(s.weights, [0.5, 0.5])


@pytest.mark.parametrize("text, reason", [
    ("lambda,a\n400,0.5\n500,-0.1\n", ":3: reflectance 'a' is negative"),
    ("lambda,a\n400,0.5\n500,nan\n", ":3: reflectance 'a' is nan"),
    ("lambda,a,b\n400,0.5,0.2\n500,0.4,inf\n", ":3: reflectance 'b' is inf"),
    ("# nothing\n", "empty set of reflectances (no data rows)"),
    ("lambda,a\n", "empty set of reflectances (no data rows)"),
    ("lambda\n400\n500\n", "empty set of reflectances"),
    ("400\n500\n", "empty set of reflectances"),
    ("lambda,a\n500,0.5\n400,0.5\n", ":3: wavelengths must increase strictly"),
    ("lambda,a\n400,0.5\n500,0.5,0.1\n", ":3: 3 columns, expected 2"),
    ("lambda,a\n400,0.5\n500,x\n", ":3: not a number: 'x'"),
    ("lambda,a\n400,0\n800,0\n", "reflectance 'a' is zero over 380-780 nm"),
])
def test_bad_reflectance_files_name_the_file_and_reason(tmp_path, text, reason):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    with pytest.raises(SpectrumError) as e:
        read_reflectances(f)
    assert str(e.value).startswith(str(f)) and reason in str(e.value)


def test_optimize_with_a_reflectance_file_end_to_end(tmp_path):
    """The real optimizer on a small problem: an accepted table whose header's J is the
    reflectance-aware J of the written table, and whose source names the set."""
    f = tmp_path / "two.csv"
    f.write_text("lambda_nm,red,blue\n" +
                 "".join(f"{w},{r},{b}\n" for w, r, b in zip([380, 480, 580, 680, 780], RED, BLUE)))
    out = tmp_path / "t.csv"
    assert cli.main(["optimize", "cie:FL2", "--reflectances", str(f), "-o", str(out),
                     "--grid-step", "20", "--max-evals", "30", "--quiet"]) == 0
    t = read_table(out)
    hdr = read_header(t)
    assert "reflectances: two (2 colours" in hdr["source"]
    p = make_problem(load_spectrum("cie:FL2"), t.grid, read_reflectances(f))
    assert objective.J(p, t.pdfs) == pytest.approx(float(hdr["J"]), rel=1e-9)
    assert float(hdr["J"]) < float(hdr["J_uniform"])


def test_bad_reflectances_on_the_command_line_exit_2(tmp_path, capsys):
    f = tmp_path / "neg.csv"
    f.write_text("lambda,a\n400,0.5\n500,-1\n")
    out = tmp_path / "t.csv"
    assert cli.main(["optimize", "cie:FL2", "--reflectances", str(f), "-o", str(out), "--quiet"]) == 2
    assert f"{f}:3: reflectance 'a' is negative" in capsys.readouterr().err
    assert cli.main(["optimize", "cie:FL2", "--reflectances", "scene", "-o", str(out), "--quiet"]) == 2
    assert "--reflectances scene needs a pbrt-v4 scene" in capsys.readouterr().err
    assert not out.exists()


def test_reflectance_fifo_and_device_are_refused_without_reading(tmp_path):
    """Regular files only (design §3.4): a FIFO blocked, /dev/zero was read without end."""
    from input_files import link_to_dev_zero, make_fifo, read_bounded

    for path in (make_fifo(tmp_path, "fifo.csv"), link_to_dev_zero(tmp_path, "zero.csv")):
        status, out = read_bounded("wavelength_pdf.reflectances:read_reflectances", path)
        assert status == 3, out
        assert out == (f"SpectrumError: {path}: not a regular file (a device, FIFO or socket), "
                       "not a reflectance file"), out
