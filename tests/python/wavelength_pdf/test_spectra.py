"""Spectrum readers (design §3): LSPDD CSV, pbrt .spd, colour-science names, malformed input."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf.spectra import (
    Spectrum,
    SpectrumError,
    _fill_gaps,
    check_support,
    load_spectra,
    load_spectrum,
    make_spectrum,
    read_lspdd_csv,
    read_spd,
)

from repo_paths import REPO  # noqa: E402
DATA = REPO / "tests" / "data" / "spectra"
from repo_paths import SHARED  # noqa: E402
LSPDD = SHARED / "spectra" / "lspdd"


# --- LSPDD CSV -----------------------------------------------------------------------

def _rows(path: Path) -> np.ndarray:
    """The (lambda, value) rows of an LSPDD-format file, parsed independently."""
    rows = [line.split(",") for line in path.read_text().splitlines()
            if line and not line.startswith("#") and not line.startswith("wavelength")]
    return np.array([[float(a), float(b)] for a, b in rows])


def test_lspdd_name_from_category_brand_model():
    sp = read_lspdd_csv(DATA / "tiny-lspdd.csv")
    assert sp.name == "Testbrand Tiny Triband (CFL)", sp.name
    assert sp.source == str(DATA / "tiny-lspdd.csv")


def test_lspdd_keeps_every_row_at_its_own_resolution():
    sp = read_lspdd_csv(DATA / "tiny-lspdd.csv")
    rows = _rows(DATA / "tiny-lspdd.csv")
    # Every measured row is a sample of the spectrum, with its value (no resampling).
    idx = np.searchsorted(sp.wavelengths, rows[:, 0])
    np.testing.assert_array_equal(sp.wavelengths[idx], rows[:, 0])
    np.testing.assert_array_equal(sp.values[idx], rows[:, 1])
    assert np.all(np.diff(sp.wavelengths) > 0)
    assert sp.wavelengths.dtype == np.float64 and sp.values.dtype == np.float64
    # Linear between neighbouring rows.
    assert sp(435.25) == pytest.approx(0.5 * (0.2 + 1.5), rel=1e-12)


def test_lspdd_gaps_are_zeros():
    """Rows with zero intensity are left out of exports: a gap longer than the base step
    (0.5 nm here) is zero from one step after the last row to one step before the next."""
    sp = read_lspdd_csv(DATA / "tiny-lspdd.csv")
    assert sp(382.0) == 0.0 and sp(434.5) == 0.0, "zeros one base step into the gap"
    for lam in (390.0, 420.0, 500.0, 580.0, 700.0):
        assert sp(lam) == 0.0, f"gap at {lam} nm must be zero, got {sp(lam)}"
    # Half a step into the gap: halfway down the ramp from the last row.
    assert sp(381.75) == pytest.approx(0.5 * 0.011, rel=1e-12)
    # Outside the rows the spectrum ramps to zero within one base step.
    assert sp(379.5) == 0.0 and sp(780.5) == 0.0 and sp(781.0) == 0.0
    assert sp(379.75) == pytest.approx(0.005, rel=1e-12)


@pytest.mark.parametrize(
    "lam, val, want_lam, want_val",
    [
        # Regular grid: only the end ramps are added.
        ([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 1.0, 2.0, 3.0, 4.0], [0, 1, 2, 3, 0]),
        # One missing row (gap = 2 steps): one zero where it was.
        ([1.0, 2.0, 4.0, 5.0], [1, 1, 1, 1], [0, 1, 2, 3, 4, 5, 6], [0, 1, 1, 0, 1, 1, 0]),
        # Several missing rows: zeros one step after and one step before.
        ([1.0, 2.0, 9.0, 10.0], [1, 1, 1, 1], [0, 1, 2, 3, 8, 9, 10, 11],
         [0, 1, 1, 0, 0, 1, 1, 0]),
    ],
)
def test_fill_gaps_cases(lam, val, want_lam, want_val):
    x, y = _fill_gaps(lam, val)
    np.testing.assert_allclose(x, want_lam, atol=1e-12)
    np.testing.assert_allclose(y, want_val, atol=0)


def test_fill_gaps_irregular_gap_stays_increasing():
    # Base step 1; a gap of 1.5 is between one and two steps: one zero in the middle.
    x, y = _fill_gaps([1.0, 2.0, 3.0, 4.5, 5.5, 6.5], [1, 1, 1, 1, 1, 1])
    assert np.all(np.diff(x) > 0), x
    assert y[list(x).index(3.75)] == 0.0


@pytest.mark.skipif(not LSPDD.is_dir(), reason="../shared/spectra/lspdd is not present")
@pytest.mark.shared
@pytest.mark.parametrize("name", sorted(p.name for p in LSPDD.glob("*.csv")) if LSPDD.is_dir() else [])
def test_every_shared_lspdd_file_reads(name):
    sp = load_spectrum(str(LSPDD / name))
    rows = _rows(LSPDD / name)
    assert sp.name and sp.name != Path(name).stem, "name comes from the Brand/Model lines"
    idx = np.searchsorted(sp.wavelengths, rows[:, 0])
    np.testing.assert_array_equal(sp.values[idx], rows[:, 1])
    check_support(sp)  # energy inside 380-780 nm


@pytest.mark.skipif(not LSPDD.is_dir(), reason="../shared/spectra/lspdd is not present")
@pytest.mark.shared
def test_shared_cfl_name():
    assert load_spectrum(str(LSPDD / "2482.csv")).name == "Globe Twister (CFL)"


# --- pbrt .spd -----------------------------------------------------------------------

def test_spd_pairs_and_comments():
    sp = read_spd(DATA / "tiny.spd")
    np.testing.assert_array_equal(sp.wavelengths, [380, 400, 450, 500, 540, 545, 550, 600, 700, 780])
    np.testing.assert_array_equal(sp.values, [0.5, 0.6, 0.8, 1.0, 1.0, 6.0, 1.0, 0.9, 0.7, 0.6])
    assert sp.name == "tiny"
    assert sp(542.5) == pytest.approx(3.5, rel=1e-12)
    assert sp(379.9) == 0.0 and sp(780.1) == 0.0


def test_spd_odd_count(tmp_path):
    f = tmp_path / "odd.spd"
    f.write_text("400 1\n500 2\n600\n")
    with pytest.raises(SpectrumError, match=rf"{f}:3: odd number"):
        read_spd(f)


# --- malformed input -----------------------------------------------------------------

@pytest.mark.parametrize(
    "name, line, reason",
    [
        ("bad-nan.csv", 6, "nan"),
        ("bad-negative.spd", 2, "negative value"),
        ("bad-no-rows.csv", 4, "no data rows"),
        ("bad-outside.spd", 2, "no energy inside"),
        ("bad-number.spd", 2, "cannot parse number"),
    ],
)
def test_malformed_files_name_file_line_reason(name, line, reason):
    path = DATA / name
    with pytest.raises(SpectrumError) as e:
        load_spectrum(str(path))
    msg = str(e.value)
    assert msg.startswith(f"{path}:{line}: "), msg
    assert reason in msg, msg


def test_missing_file():
    with pytest.raises(SpectrumError, match="no such file"):
        load_spectrum(str(DATA / "does-not-exist.csv"))
    with pytest.raises(SpectrumError, match="no such file"):
        load_spectrum("nowhere/lamp.spd")


@pytest.mark.parametrize(
    "text, line, reason",
    [
        ("wavelength, intensity\n400,1\n500,2,3\n", 3, "2 comma-separated columns"),
        ("wavelength, intensity\n400,1\n500,inf\n", 3, "must be finite"),
        ("wavelength, intensity\n500,1\n400,1\n", 3, "strictly increasing"),
        ("wavelength, intensity\n400,1\n", 2, "at least 2 samples"),
        ("lambda;value\n400;1\n", 1, "expected the header"),
    ],
)
def test_malformed_csv_variants(tmp_path, text, line, reason):
    f = tmp_path / "lamp.csv"
    f.write_text(text)
    with pytest.raises(SpectrumError) as e:
        read_lspdd_csv(f)
    assert str(e.value).startswith(f"{f}:{line}: ") and reason in str(e.value), str(e.value)


def test_unknown_format(tmp_path):
    f = tmp_path / "lamp.txt"
    f.write_text("400 1\n")
    with pytest.raises(SpectrumError, match="unknown spectrum format"):
        load_spectrum(str(f))


# --- support -------------------------------------------------------------------------

def test_check_support_boundaries():
    # Energy only above 780 nm (the ramp starts exactly at 780): nothing inside.
    sp = make_spectrum("ir", "test", [780.0, 790.0], [0.0, 1.0])
    with pytest.raises(SpectrumError, match="no energy inside"):
        check_support(sp)
    # A little energy inside is enough.
    check_support(make_spectrum("edge", "test", [779.0, 790.0], [1.0, 1.0]))
    # A custom range moves the test.
    check_support(sp, 700.0, 800.0)
    with pytest.raises(SpectrumError, match=r"t: spectrum 'red' has no energy inside \[380, 500\]"):
        check_support(make_spectrum("red", "t", [600.0, 700.0], [1.0, 1.0]), 380.0, 500.0)
    # The readers check the range they are given.
    with pytest.raises(SpectrumError, match=r"tiny.spd:\d+: .*\[790, 800\]"):
        load_spectrum(str(DATA / "tiny.spd"), lo=790.0, hi=800.0)


def test_spectrum_is_read_only():
    sp = make_spectrum("x", "t", [400.0, 500.0], [1.0, 2.0])
    with pytest.raises(ValueError):
        sp.values[0] = 5.0
    assert isinstance(sp, Spectrum)


# --- colour-science names ------------------------------------------------------------

@pytest.mark.parametrize("name", ["A", "D65"] + [f"FL{i}" for i in range(1, 13)]
                         + [f"HP{i}" for i in range(1, 6)])
def test_cie_illuminants(name):
    import colour

    sp = load_spectrum(f"cie:{name}")
    sd = colour.SDS_ILLUMINANTS[name]
    np.testing.assert_array_equal(sp.wavelengths, sd.wavelengths)
    np.testing.assert_array_equal(sp.values, sd.values)
    assert sp.name == name and sp.source == f"cie:{name}"


def test_names_ignore_case_and_unknown_names_list_the_known():
    assert load_spectrum("cie:fl11").name == "FL11"
    assert load_spectrum("lamp:mercury").name == "Mercury"
    with pytest.raises(SpectrumError, match=r"cie:FL99: unknown CIE illuminant; known names: .*FL11"):
        load_spectrum("cie:FL99")
    with pytest.raises(SpectrumError, match="unknown light source"):
        load_spectrum("lamp:No Such Lamp")


def test_load_spectra_returns_one_for_a_file():
    sps = load_spectra(str(DATA / "tiny.spd"))
    assert len(sps) == 1 and sps[0].name == "tiny"


# --- the project's own spectra -------------------------------------------------------

def test_shipped_spectra():
    tri = load_spectrum(str(REPO / "spectra" / "tri-band-fluorescent.spd"))
    for line in (435.8, 546.1, 611.0):
        near = (tri.wavelengths > line - 3) & (tri.wavelengths < line + 3)
        far = (tri.wavelengths > line - 30) & (tri.wavelengths < line - 10)
        assert tri.values[near].max() > 10 * tri.values[far].max(), f"line at {line} nm"
    led = load_spectrum(str(REPO / "spectra" / "white-led.csv"))
    assert led.name == "Synthetic Blue pump + YAG phosphor (LED)"
    assert abs(led.wavelengths[np.argmax(led.values)] - 450.0) <= 1.0
    na = load_spectrum(str(REPO / "spectra" / "sodium-2nm-line.spd"))
    assert np.all(na(np.arange(380.0, 781.0, 5.0)) == 0.0), "zero at every 5 nm node"


def test_reader_registry_dispatches_by_suffix(tmp_path, monkeypatch):
    """A registered reader gets (path, selector, lo, hi); unknown suffixes list the known."""
    from wavelength_pdf import spectra as sp_mod

    monkeypatch.setattr(sp_mod, "READERS", dict(sp_mod.READERS))
    seen = []

    def reader(path, selector, lo, hi):
        seen.append((path, selector, lo, hi))
        return [sp_mod.make_spectrum("two", path, [400.0, 700.0], [1.0, 1.0])]

    sp_mod.register_reader(".TWO", reader)
    f = tmp_path / "a.two"
    f.write_text("")
    assert [s.name for s in sp_mod.load_spectra(str(f), lo=390.0, hi=710.0)] == ["two"]
    assert seen == [(str(f), None, 390.0, 710.0)]
    (tmp_path / "b.xyz").write_text("")
    with pytest.raises(sp_mod.SpectrumError, match=r"unknown spectrum format '\.xyz'.*\.two"):
        sp_mod.load_spectra(str(tmp_path / "b.xyz"))


# --- what is not a spectrum file (design §3.3: regular files of at most 64 MiB) --------

from input_files import link_to_dev_zero, make_fifo, read_bounded  # noqa: E402


@pytest.mark.parametrize("suffix", [".spd", ".csv"])
def test_fifo_and_device_are_refused_without_reading(tmp_path, suffix):
    """A FIFO named as a spectrum blocked for ever; /dev/zero was read until a MemoryError."""
    for path in (make_fifo(tmp_path, f"fifo{suffix}"), link_to_dev_zero(tmp_path, f"zero{suffix}")):
        status, out = read_bounded("wavelength_pdf.spectra:load_spectrum", path)
        assert status == 3, out
        assert out == (f"SpectrumError: {path}: not a regular file (a device, FIFO or socket), "
                       "not a spectrum file"), out


def test_spectrum_larger_than_64_mib_is_refused(tmp_path):
    path = tmp_path / "big.spd"
    with open(path, "w") as fh:
        fh.write("400 1\n500 1\n600 1\n")
        fh.write(("#" + "x" * 1023 + "\n") * (64 * 1024))  # valid, padded with comments
    with pytest.raises(SpectrumError) as e:
        load_spectrum(str(path))
    assert str(e.value) == f"{path}: larger than 64 MiB, not a spectrum file"
