"""colour-science's data through the on-disk copy: the same numbers, and a cache folder
that cannot be written never fails a run."""

import os

import numpy as np
import pytest

from wavelength_pdf import colour_data


@pytest.fixture()
def fresh(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("WAVELENGTH_PDF_DATA_CACHE", raising=False)
    colour_data._data.cache_clear()
    yield tmp_path
    colour_data._data.cache_clear()


def test_the_copy_holds_colour_sciences_numbers(fresh):
    import colour

    wl, val = colour_data.cmfs()  # first use: from colour-science, and written
    assert list(fresh.glob("wavelength-pdf/colour-science-*.npz"))
    colour_data._data.cache_clear()
    wl2, val2 = colour_data.cmfs()  # read back from the copy
    c = colour.MSDS_CMFS[colour_data.OBSERVER]
    assert np.array_equal(wl2, c.wavelengths) and np.array_equal(val2, c.values)
    assert np.array_equal(wl, wl2) and np.array_equal(val, val2)
    for kind, table in (("illuminants", colour.SDS_ILLUMINANTS), ("light_sources", colour.SDS_LIGHT_SOURCES)):
        got = colour_data.spectra(kind)
        assert list(got) == list(table.keys())
        for name in ("FL11", "Mercury", "A"):
            if name in table:
                assert np.array_equal(got[name][0], table[name].wavelengths)
                assert np.array_equal(got[name][1], table[name].values)
    xyz = colour_data.white_d65()
    assert xyz[1] == pytest.approx(1.0) and xyz[0] == pytest.approx(0.3127 / 0.3290, rel=1e-4)


def test_a_read_only_or_damaged_cache_is_skipped(fresh):
    folder = fresh / "wavelength-pdf"
    folder.mkdir()
    os.chmod(folder, 0o500)
    try:
        wl, _ = colour_data.cmfs()
        assert wl.size > 400
    finally:
        os.chmod(folder, 0o700)
    colour_data._data.cache_clear()
    path = colour_data._cache_path()
    path.write_bytes(b"not an npz file")
    assert colour_data.cmfs()[0].size == wl.size
    with pytest.raises(ValueError):
        colour_data.spectra("nonsense")
