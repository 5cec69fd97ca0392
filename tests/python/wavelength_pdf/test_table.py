"""The table file (design §2): round trip, both layouts, normalization, malformed input, atomic write."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf import table as table_mod
from wavelength_pdf.table import HEADER, Table, TableError, read_table, write_table

from repo_paths import REPO  # noqa: E402
from input_files import (EDGE_TABLES, edge_table_cases, link_to_dev_zero,  # noqa: E402
                         make_fifo, read_bounded, same_table_pairs)
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


@pytest.mark.parametrize("name, same_as", same_table_pairs(),
                         ids=[f"{a}={b}" for a, b in same_table_pairs()])
def test_edge_tables_that_are_the_same_table(name, same_as):
    """The pairs of tests/data/tables/edge/same.csv, which the header's test reads too: line
    ends, blanks and a byte-order mark change nothing, both layouts give one table, and a
    table's densities are its exact renormalization (the *-normalized.csv files) to rounding."""
    a, b = read_table(EDGE_TABLES / name), read_table(EDGE_TABLES / same_as)
    np.testing.assert_array_equal(a.grid, b.grid)
    np.testing.assert_allclose(a.pdfs, b.pdfs, rtol=1e-14, atol=0)


def test_a_normalized_table_reads_back_bit_for_bit():
    """design §2.3: a table written normalized is not scaled (the -normalized.csv files hold
    the exact renormalization of their pair, so their mass is 1 to rounding)."""
    for _, same_as in same_table_pairs():
        if same_as.endswith("-normalized.csv"):
            text = (EDGE_TABLES / same_as).read_text().splitlines()
            written = np.array([[float(v) for v in row.split(",")] for row in text[2:]])
            t = read_table(EDGE_TABLES / same_as)
            np.testing.assert_array_equal(t.pdfs, written[:, 1:].T)


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


def test_table_larger_than_64_mib_is_refused_before_it_is_read(tmp_path):
    """design §2.3: 64 MiB + 1 bytes are refused for their size; 64 MiB are read (here NUL
    bytes, refused at line 1 for what they are). Sparse files: nothing is written to disk."""
    limit = 64 << 20
    for size, reason in ((limit, "1: control character U+0000"),
                         (limit + 1, " larger than 64 MiB, not a table file")):
        path = tmp_path / f"{size}.csv"
        with open(path, "wb") as fh:
            fh.truncate(size)
        with pytest.raises(TableError) as e:
            read_table(path)
        assert str(e.value).startswith(f"{path}:{reason}"), str(e.value)


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
