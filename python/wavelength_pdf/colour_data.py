"""colour-science's tabulated data without importing colour-science on every run.

Importing colour-science takes 1-1.5 s of CPU (it imports matplotlib for its plotting
package), a quarter of what optimizing one spectrum costs. The few tables this package
reads from it (the CIE 1931 2-degree colour matching functions, the D65 white, the
illuminants and light sources by name) are copied on first use into
``$XDG_CACHE_HOME/wavelength-pdf/colour-science-VERSION.npz`` (``~/.cache/...``), keyed by
the installed colour-science version, and read from there afterwards. A cache that
cannot be written or read is skipped silently: colour-science is then imported as before.
``WAVELENGTH_PDF_DATA_CACHE=off`` turns the cache off.
"""

from __future__ import annotations

import os
import tempfile
from functools import lru_cache
from importlib import metadata
from pathlib import Path

import numpy as np

#: colour-science's name of the CIE 1931 2-degree standard observer.
OBSERVER = "CIE 1931 2 Degree Standard Observer"

_KINDS = ("illuminants", "light_sources")


def _cache_path() -> Path | None:
    env = os.environ.get("WAVELENGTH_PDF_DATA_CACHE")
    if env is not None and env.strip().lower() in ("", "off", "0", "no"):
        return None
    try:
        version = metadata.version("colour-science")
    except metadata.PackageNotFoundError:
        return None
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "wavelength-pdf" / f"colour-science-{version}.npz"


def _from_colour() -> dict:
    import colour

    c = colour.MSDS_CMFS[OBSERVER]
    xy = colour.CCS_ILLUMINANTS[OBSERVER]["D65"]
    data = {
        "cmf_wl": np.asarray(c.wavelengths, dtype=np.float64),
        "cmf_val": np.asarray(c.values, dtype=np.float64),
        "white_d65": np.asarray(colour.xyY_to_XYZ(colour.xy_to_xyY(xy)), dtype=np.float64),
    }
    for kind, table in zip(_KINDS, (colour.SDS_ILLUMINANTS, colour.SDS_LIGHT_SOURCES)):
        names = list(table.keys())
        wls = [np.asarray(table[k].wavelengths, dtype=np.float64) for k in names]
        vals = [np.asarray(table[k].values, dtype=np.float64) for k in names]
        data[f"{kind}_names"] = np.array(names, dtype=str)
        data[f"{kind}_offsets"] = np.cumsum([0] + [w.size for w in wls])
        data[f"{kind}_wl"] = np.concatenate(wls)
        data[f"{kind}_val"] = np.concatenate(vals)
    return data


def _write(path: Path, data: dict) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".colour-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **data)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    except OSError:
        pass  # read-only or full cache folder: colour-science is imported next time too


@lru_cache(maxsize=1)
def _data() -> dict:
    path = _cache_path()
    if path is not None and path.is_file():
        try:
            with np.load(path, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (OSError, ValueError, KeyError, EOFError):
            pass  # damaged: rebuilt below
    data = _from_colour()
    if path is not None:
        _write(path, data)
    return data


def cmfs() -> tuple[np.ndarray, np.ndarray]:
    """CIE 1931 2-degree CMFs as colour-science tabulates them: (wavelengths, (K, 3))."""
    d = _data()
    return d["cmf_wl"].copy(), d["cmf_val"].copy()


def white_d65() -> np.ndarray:
    """XYZ of the D65 white (Y = 1), as colour-science computes it from its xy."""
    return _data()["white_d65"].copy()


def spectra(kind: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """colour-science's ``SDS_ILLUMINANTS`` (``kind="illuminants"``) or
    ``SDS_LIGHT_SOURCES`` (``"light_sources"``): name -> (wavelengths, values)."""
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, not {kind!r}")
    d = _data()
    names, off = d[f"{kind}_names"], d[f"{kind}_offsets"]
    wl, val = d[f"{kind}_wl"], d[f"{kind}_val"]
    return {str(n): (wl[a:b].copy(), val[a:b].copy()) for n, a, b in zip(names, off[:-1], off[1:])}
