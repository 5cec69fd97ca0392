"""The table file (design §2): round trip, both layouts, normalization, malformed input, atomic write."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf import table as table_mod
from wavelength_pdf.table import HEADER, Table, TableError, read_table, write_table

REPO = Path(__file__).resolve().parents[2]
from input_files import (EDGE_TABLES, edge_table_cases, link_to_dev_zero,  # noqa: E402
                         make_fifo, read_bounded)
from repo_paths import SHARED  # noqa: E402

REFERENCE = SHARED / "tables" / "reference-4x81"


def _trapezoid(grid, pdfs):
    return np.sum(0.5 * (pdfs[:, 1:] + pdfs[:, :-1]) * np.diff(grid), axis=1)


def _random_table(seed: int, n: int = 37) -> Table:
    rng = np.random.default_rng(seed)
    grid = np.sort(380.0 + 400.0 * rng.random(n))
    grid[0], grid[-1] = 380.0, 780.0
    pdfs = rng.random((4, n)) ** 3
    pdfs[1, : n // 2] = 0.0  # exact zeros survive the trip
    pdfs /= _trapezoid(grid, pdfs)[:, None]
    return Table(grid=grid, pdfs=pdfs, comments=["name: test lamp", "J: 0.125", "x:y: z"])


# --- round trip ----------------------------------------------------------------------

@pytest.mark.parametrize("seed", [0, 1, 2])
def test_round_trip_is_exact(tmp_path, seed):
    t = _random_table(seed)
    path = tmp_path / "t.csv"
    write_table(path, t)
    back = read_table(path)
    np.testing.assert_array_equal(back.grid, t.grid)
    np.testing.assert_array_equal(back.pdfs, t.pdfs)  # bit for bit: repr-precision numbers
    assert back.comments == t.comments
    text = path.read_text().splitlines()
    assert text[0].startswith("# ") and HEADER in text
    assert len(text) == len(t.comments) + 1 + t.grid.size


def test_writer_renormalization_free_and_reader_normalizes(tmp_path):
    path = tmp_path / "raw.csv"
    path.write_text("# unnormalized\nlambda_nm,pdf0,pdf1,pdf2,pdf3\n"
                    "400,1,0,2,5\n500,1,3,2,5\n600,1,0,0,5\n")
    t = read_table(path)
    np.testing.assert_allclose(_trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-15)
    # Proportional to the file's values (the shape is kept).
    np.testing.assert_allclose(t.pdfs[0], [1 / 200] * 3, rtol=1e-15)
    np.testing.assert_allclose(t.pdfs[1], [0, 3 / 300, 0], rtol=1e-15)
    np.testing.assert_allclose(t.pdfs[2], [2 / 300, 2 / 300, 0], rtol=1e-15)
    assert t.comments == ["unnormalized"]


# --- the 4 x 81 layout ---------------------------------------------------------------

def test_4x81_layout_with_trailing_commas(tmp_path):
    rng = np.random.default_rng(5)
    raw = rng.random((4, 81)) + 0.1
    path = tmp_path / "old.csv"
    path.write_text("".join(",".join(repr(float(v)) for v in row) + ",\n" for row in raw))
    t = read_table(path)
    np.testing.assert_array_equal(t.grid, np.linspace(380.0, 780.0, 81))
    np.testing.assert_allclose(_trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-14)
    ratio = t.pdfs / raw
    np.testing.assert_allclose(ratio, ratio[:, :1] * np.ones((1, 81)), rtol=1e-14)


@pytest.mark.shared
@pytest.mark.skipif(not REFERENCE.is_dir(), reason="../shared/tables/reference-4x81 is not present")
@pytest.mark.parametrize("name", sorted(p.name for p in REFERENCE.glob("*.csv")) if REFERENCE.is_dir() else [])
def test_every_reference_table_reads(name):
    path = REFERENCE / name
    raw = np.array([[float(v) for v in line.split(",") if v.strip()]
                    for line in path.read_text().splitlines() if line.strip()])
    t = read_table(path)
    assert t.pdfs.shape == (4, 81) and raw.shape == (4, 81)
    np.testing.assert_allclose(_trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-13)
    scale = _trapezoid(t.grid, raw)
    np.testing.assert_allclose(t.pdfs * scale[:, None], raw, rtol=1e-13, atol=0)


# --- malformed input -----------------------------------------------------------------

_OK_ROWS = ["380,1,1,1,1", "580,1,1,1,1", "780,1,1,1,1"]


def _csv(rows: list[str]) -> str:
    return "# comment\n" + HEADER + "\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize(
    "text, line, reason",
    [
        (_csv(["380,1,1,1,1", "580,nan,1,1,1", "780,1,1,1,1"]), 4, "pdf0 is NaN"),
        (_csv(["380,1,1,1,1", "580,1,inf,1,1", "780,1,1,1,1"]), 4, "pdf1 is infinite"),
        (_csv(["380,1,1,1,1", "580,1,1,-0.5,1", "780,1,1,1,1"]), 4, "pdf2 is negative"),
        (_csv(["380,1,1,1,0", "580,1,1,1,0", "780,1,1,1,0"]), 3, "pdf3 is zero everywhere"),
        (_csv(["380,1,1,1,1", "580,1,1,1,1", "580,1,1,1,1"]), 5, "not strictly increasing"),
        (_csv(["380,1,1,1,1", "780,1,1,1,1", "580,1,1,1,1"]), 5, "not strictly increasing"),
        (_csv(["380,1,1,1,1", "580,1,1,1", "780,1,1,1,1"]), 4, "4 columns, expected 5"),
        (_csv(["380,1,1,1,1", "580,1,1,1,1,1", "780,1,1,1,1"]), 4, "6 columns, expected 5"),
        (_csv(["380,1,1,1,1"]), 3, "at least 2 grid nodes"),
        (_csv(["380,1,1,1,1", "580,1,x,1,1"]), 4, "cannot parse number 'x'"),
        ("# only a header\n" + HEADER + "\n", 2, "no data rows"),
        ("lambda_nm,pdf0,pdf1\n380,1,1\n", 1, "header has 3 columns"),
        ("\n".join(",".join(["1"] * 81) for _ in range(3)) + "\n", 3, "3 rows of densities"),
        ("\n".join(",".join(["1"] * (80 if i == 2 else 81)) for i in range(4)) + "\n", 3,
         "80 densities, expected 81"),
        ("\n".join(",".join(["1"] * 81) if i != 1 else ",".join(["1"] * 80 + ["nan"])
                   for i in range(4)) + "\n", 2, "pdf1 is NaN at 780 nm"),
    ],
)
def test_malformed_tables_name_file_line_reason(tmp_path, text, line, reason):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(TableError) as e:
        read_table(path)
    msg = str(e.value)
    assert msg.startswith(f"{path}:{line}: "), msg
    assert reason in msg, msg


# --- the edge cases every table reader reads alike (tests/data/tables/edge) ----------

@pytest.mark.parametrize("name, nodes, line, reason", edge_table_cases(),
                         ids=[c[0] for c in edge_table_cases()])
def test_edge_tables_as_every_reader_reads_them(name, nodes, line, reason):
    """The same files and expectations as the C++ header's and the renderer's tests: what a
    line is, which characters a table may hold, what a number is (design §2), and exact
    renormalization of densities at the extremes of double precision (§2.3)."""
    path = EDGE_TABLES / name
    if nodes is None:
        with pytest.raises(TableError) as e:
            read_table(path)
        msg = str(e.value)
        assert msg.startswith(f"{path}:{line}: "), msg
        assert reason in msg, msg
        return
    t = read_table(path)
    assert t.grid.size == nodes
    np.testing.assert_allclose(_trapezoid(t.grid, t.pdfs), 1.0, rtol=1e-13)
    assert np.all(np.isfinite(t.pdfs)) and np.all(t.pdfs >= 0)


def test_subnormal_densities_are_renormalized_exactly():
    """Densities of 5e-324 each are a uniform density: integrated in subnormal numbers
    their mass came out 16 % off, and pbrt rendered a 5 % - 25 % too dark image."""
    t = read_table(EDGE_TABLES / "denormal.csv")
    span = t.grid[-1] - t.grid[0]
    np.testing.assert_allclose(t.pdfs, 1.0 / span, rtol=1e-13)
    # A shape in subnormal units keeps its shape: the triangle rises linearly.
    s = read_table(EDGE_TABLES / "denormal-shaped.csv")
    np.testing.assert_allclose(_trapezoid(s.grid, s.pdfs), 1.0, rtol=1e-13)
    np.testing.assert_allclose(s.pdfs[0][1:100] / s.pdfs[0][1], np.arange(1, 100), rtol=1e-15)


def test_writer_drops_control_characters_from_comments(tmp_path):
    t = _random_table(7)
    t.comments = ["name: lamp\x1b[31m red", "a\fb", "nul\x00 here"]
    write_table(tmp_path / "t.csv", t)
    back = read_table(tmp_path / "t.csv")  # would refuse a control character
    assert back.comments == ["name: lamp [31m red", "a", "b", "nul  here"]


# --- what is not a table file (design §2.3: regular files of at most 64 MiB) ----------

def test_fifo_and_device_are_refused_without_reading(tmp_path):
    """A FIFO blocked the reader for ever; /dev/zero was read until memory ran out."""
    for path in (make_fifo(tmp_path, "fifo.csv"), link_to_dev_zero(tmp_path, "zero.csv")):
        status, out = read_bounded("wavelength_pdf.table:read_table", path)
        assert status == 3, out
        assert out == f"TableError: {path}: not a regular file (a device, FIFO or socket), not a " \
                      "table file", out


def test_table_larger_than_64_mib_is_refused(tmp_path):
    path = tmp_path / "big.csv"
    with open(path, "w") as fh:
        fh.write(HEADER + "\n380,1,1,1,1\n780,1,1,1,1\n")
        line = "#" + "x" * 1023 + "\n"
        fh.write(line * (64 * 1024))  # a valid table, padded past 64 MiB with comments
    assert path.stat().st_size > 64 << 20
    with pytest.raises(TableError) as e:
        read_table(path)
    assert str(e.value) == f"{path}: larger than 64 MiB, not a table file"


def test_missing_file(tmp_path):
    with pytest.raises(TableError, match=rf"{tmp_path / 'none.csv'}: no such file"):
        read_table(tmp_path / "none.csv")


# --- atomic write --------------------------------------------------------------------

def test_bad_table_is_not_written_and_old_file_survives(tmp_path):
    path = tmp_path / "t.csv"
    good = _random_table(3)
    write_table(path, good)
    before = path.read_bytes()
    bad = Table(grid=good.grid, pdfs=good.pdfs.copy(), comments=[])
    bad.pdfs[2, 4] = np.nan
    with pytest.raises(TableError, match="not written.*pdf2 is NaN"):
        write_table(path, bad)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"], "no temporary files left"
    with pytest.raises(TableError, match="zero everywhere"):
        write_table(tmp_path / "z.csv", Table(good.grid, np.zeros_like(good.pdfs)))
    assert not (tmp_path / "z.csv").exists()


def test_failure_during_write_leaves_old_file(tmp_path, monkeypatch):
    path = tmp_path / "t.csv"
    write_table(path, _random_table(4))
    before = path.read_bytes()

    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(table_mod.os, "replace", fail)
    with pytest.raises(OSError):
        write_table(path, _random_table(5))
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"], "temporary file removed"


def test_written_file_has_ordinary_permissions(tmp_path):
    path = tmp_path / "t.csv"
    write_table(path, _random_table(6))
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_directory_is_named_as_such(tmp_path):
    with pytest.raises(TableError) as e:
        read_table(tmp_path)
    assert str(e.value) == f"{tmp_path}: is a directory, not a table file"
