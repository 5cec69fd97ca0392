"""Sets of surface reflectances for the reflectance-aware objective (design §3.4, §4.5).

The objective of design §4.1 scores one lamp seen on a white surface. With a set of surface
colours R_1 .. R_K, J becomes the weighted mean over k of J with f = I * R_k * cmf
(:func:`wavelength_pdf.problem.make_problem` with ``reflectances=``). A set is named by

- ``colorchecker`` -- the 24 patches of the ColorChecker as colour-science ships them
  (``colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]``, 380-780 nm in 5 nm steps);
- ``scene``        -- the reflectances of a pbrt-v4 scene's materials, as the renderer builds
  them (``pbrt --material-reflectances``, design §5.6): RGB albedos through the renderer's
  own sigmoid-polynomial tables, spectra as written, textures by their mean;
- anything else    -- a reflectance file (design §3.4): a CSV whose first column is the
  wavelength in nm and every further column one reflectance.

Every colour weighs the same (weights 1/K). A reflectance is linear between its samples and
keeps its end values beyond them (a surface does not turn black where its measurement
stops). Bad input is a :class:`~wavelength_pdf.spectra.SpectrumError` naming the file, the
line and the reason.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wavelength_pdf.files import MAX_INPUT_BYTES, InputFileError, read_regular_file
from wavelength_pdf.spectra import SpectrumError

__all__ = ["ReflectanceSet", "colorchecker", "read_reflectances", "scene_reflectances",
           "load_reflectances", "colours_label", "REFLECTANCE_SETS"]

#: The names ``--reflectances`` takes besides a file.
REFLECTANCE_SETS = ("scene", "colorchecker")
#: ``--reflectances white``: no set, the one white surface of design §4.1.
WHITE = "white"


@dataclass(frozen=True)
class ReflectanceSet:
    """K surface reflectances on one wavelength grid.

    Attributes
    ----------
    name : str
        Short name (``colorchecker``, ``scene``, the file's stem).
    source : str
        Where it came from.
    wavelengths : (L,) float64 array, nm, strictly increasing
    values : (K, L) float64 array, finite and >= 0
    labels : tuple of str
        One name per reflectance.
    weights : (K,) float64 array
        Weight of each colour in J (equal, summing to 1).
    """

    name: str
    source: str
    wavelengths: np.ndarray
    values: np.ndarray
    labels: tuple[str, ...]
    weights: np.ndarray

    def __len__(self) -> int:
        return int(self.values.shape[0])


def _make(name: str, source: str, wl, values, labels, where: str, lo: float, hi: float,
          lines: list[int] | None = None) -> ReflectanceSet:
    """Validate and build a set (errors name ``where`` and, when known, the line)."""
    wl = np.asarray(wl, dtype=np.float64)
    vals = np.atleast_2d(np.asarray(values, dtype=np.float64))
    if vals.size == 0 or vals.shape[0] == 0:
        raise SpectrumError(f"{where}: empty set of reflectances (no reflectance column)")
    if wl.size < 2:
        raise SpectrumError(f"{where}: a reflectance needs at least 2 wavelengths, got {wl.size}")

    def at(i: int) -> str:
        return f"{where}:{lines[i]}" if lines else where

    for i in range(wl.size):
        if not np.isfinite(wl[i]):
            raise SpectrumError(f"{at(i)}: wavelength is {wl[i]}")
        if i and not wl[i] > wl[i - 1]:
            raise SpectrumError(f"{at(i)}: wavelengths must increase strictly "
                                f"({wl[i - 1]:g} then {wl[i]:g})")
    for k, label in enumerate(labels):
        bad = ~np.isfinite(vals[k])
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise SpectrumError(f"{at(i)}: reflectance {label!r} is {vals[k, i]} at "
                                f"{wl[i]:g} nm (NaN or infinity)")
        neg = vals[k] < 0
        if neg.any():
            i = int(np.flatnonzero(neg)[0])
            raise SpectrumError(f"{at(i)}: reflectance {label!r} is negative ({vals[k, i]:g}) "
                                f"at {wl[i]:g} nm")
        inside = np.interp(np.linspace(lo, hi, 401), wl, vals[k])
        if not inside.max() > 0:
            raise SpectrumError(f"{where}: reflectance {label!r} is zero over {lo:g}-{hi:g} nm "
                                f"(a black surface has no colour to estimate)")
    k = vals.shape[0]
    return ReflectanceSet(name=name, source=source, wavelengths=wl, values=vals,
                          labels=tuple(labels), weights=np.full(k, 1.0 / k))


def colorchecker(lo: float = 380.0, hi: float = 780.0) -> ReflectanceSet:
    """The 24 ColorChecker patches colour-science ships (N. Ohta's measurements)."""
    import colour

    key = "ColorChecker N Ohta"
    sds = colour.SDS_COLOURCHECKERS[key]
    names = list(sds)
    wl = np.asarray(sds[names[0]].wavelengths, dtype=np.float64)
    vals = np.stack([np.asarray(sds[n].values, dtype=np.float64) for n in names])
    return _make("colorchecker", f"colour.SDS_COLOURCHECKERS[{key!r}]", wl, vals, names,
                 "colorchecker", lo, hi)


_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$|^[+-]?(nan|inf|infinity)$",
                     re.IGNORECASE)


def read_reflectances(path: str | os.PathLike, lo: float = 380.0,
                      hi: float = 780.0) -> ReflectanceSet:
    """A reflectance file (design §3.4).

    ``#`` starts a comment line; blank lines are skipped. An optional header row
    (``lambda_nm,NAME1,NAME2,...``: any row whose cells are not all numbers) names the
    columns; then one row per wavelength: the wavelength in nm, strictly increasing, and one
    value per reflectance, finite and >= 0. Columns are separated by commas (or, when a
    row has none, by whitespace).
    """
    path = Path(path)
    where = str(path)
    # A regular file of at most 64 MiB (design §3.4): a device or FIFO fails at once.
    try:
        text = read_regular_file(path, "reflectance", MAX_INPUT_BYTES).decode("utf-8-sig")
    except InputFileError as e:
        if e.reason == "no such file":
            raise SpectrumError(f"{where}: no such reflectance file") from None
        raise SpectrumError(str(e)) from None
    except UnicodeDecodeError as e:
        raise SpectrumError(f"{where}: cannot read ({e})") from None
    header: list[str] | None = None
    rows: list[list[float]] = []
    lines: list[int] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        cells = [c.strip() for c in (s.split(",") if "," in s else s.split())]
        if not all(_NUMBER.match(c) for c in cells):
            if rows or header is not None:
                bad = next(c for c in cells if not _NUMBER.match(c))
                raise SpectrumError(f"{where}:{lineno}: not a number: {bad!r}")
            header = cells
            if len(header) < 2:
                raise SpectrumError(f"{where}:{lineno}: empty set of reflectances (the header "
                                    f"names no reflectance column after the wavelength)")
            continue
        ncol = len(header) if header is not None else (len(rows[0]) if rows else len(cells))
        if len(cells) != ncol:
            raise SpectrumError(f"{where}:{lineno}: {len(cells)} columns, expected {ncol} "
                                f"(the wavelength and one value per reflectance)")
        if ncol < 2:
            raise SpectrumError(f"{where}:{lineno}: empty set of reflectances (only a "
                                f"wavelength column)")
        rows.append([float(c) for c in cells])
        lines.append(lineno)
    if not rows:
        raise SpectrumError(f"{where}: empty set of reflectances (no data rows)")
    data = np.asarray(rows, dtype=np.float64)
    k = data.shape[1] - 1
    labels = header[1:] if header is not None else [f"{path.stem}#{i}" for i in range(k)]
    return _make(path.stem, where, data[:, 0], data[:, 1:].T, labels, where, lo, hi, lines)


def scene_reflectances(scene: str | os.PathLike, lo: float = 380.0, hi: float = 780.0,
                       pbrt: str | os.PathLike | None = None) -> ReflectanceSet:
    """The reflectances of a scene's materials as the renderer builds them (design §5.6).

    Runs ``pbrt --material-reflectances`` (found as the evaluation finds it, design §7) and
    reads its CSV: one column per material that shapes use and that has a diffuse
    reflectance, RGB albedos turned into spectra by the renderer's own tables, textures by
    their mean.
    """
    from wavelength_pdf.scene_spectra import renderer_output

    with renderer_output(Path(scene), "--material-reflectances", "materials.csv",
                         "material reflectances", pbrt) as out:
        got = read_reflectances(out, lo, hi)
    return ReflectanceSet(name="scene", source=f"{scene} (materials: pbrt --material-reflectances)",
                          wavelengths=got.wavelengths, values=got.values, labels=got.labels,
                          weights=got.weights)


def load_reflectances(spec: str, scene: str | os.PathLike | None = None, lo: float = 380.0,
                      hi: float = 780.0, pbrt: str | os.PathLike | None = None) -> ReflectanceSet:
    """``--reflectances SET``: ``scene`` (needs ``scene``), ``colorchecker`` or a file."""
    if spec == "white":
        raise SpectrumError("'white' is the surface of design §4.1, not a set of reflectances "
                            "(optimize without reflectances)")
    if spec == "colorchecker":
        return colorchecker(lo, hi)
    if spec == "scene":
        if scene is None or not str(scene).lower().endswith(".pbrt"):
            raise SpectrumError("--reflectances scene needs a pbrt-v4 scene (.pbrt) as the "
                                "spectrum to optimize for")
        return scene_reflectances(scene, lo, hi, pbrt)
    return read_reflectances(spec, lo, hi)


def colours_label(reflectances: ReflectanceSet | None) -> str:
    """How a table's record names the surface colours it was made for (its ``source`` line
    after ``; reflectances: ``): '' for the white surface of design §4.1."""
    if reflectances is None:
        return ""
    return f"{reflectances.name} ({len(reflectances)} colours, {reflectances.source})"
