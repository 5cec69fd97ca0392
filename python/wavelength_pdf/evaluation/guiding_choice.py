"""Which table for each of wavelength guiding's mixtures: emission's or an optimized one, by the
image error each is predicted to give over the pixels that mixture lights (design §1.8, §6.8).

An optimized mixture table that the optimizer accepts (its J below its start's, design §4.4)
can still be worse in the image than the mixture's emission table: on the benchmark's night
street the tables optimized for the white surface lose a tenth to two fifths where the white
LED dominates (docs/guiding.md). J scores one path on one surface; the pixel prediction of
:mod:`wavelength_pdf.evaluation.choose` (each pixel's own light, its incoherence and
dispersion, the spp rendered at) ranks samplers as the images do (docs/benchmark.md). Here it
is applied per guiding table:

- the tile map (``tiles.txt``) and the mixtures (``mixture-HASH.spd``, ``clusters.txt``) come
  from ``pbrt --wavelength-guiding-spectra DIR`` at the render's settings (design §5.2);
- the scene's transfer (:mod:`.transfer`: every emitter flat, a spectral film) gives each
  pixel's spectral transfer t_p; a pixel of table k is modelled as lit by that table's mixture
  m_k (its spectrum m_k(λ) t_p(λ) in the basis). This is exact when every kind of light reaches
  the pixel by the same paths in the table's proportions, which the clustering makes roughly
  so; it is an approximation, not the scene's own light;
- each candidate is predicted as the renderer samples it: ``emission`` is the table that run
  wrote (``table-K.txt``: design §1.7's stratified table of the mixture with the defensive
  share), each folder's ``mixture-HASH.csv`` is mixed with the defensive spectrum
  (``defensive.txt``) as the renderer mixes it (design §1.8). The prediction is the mean over
  table k's pixels of :func:`wavelength_pdf.predict.pixel_de2`. (Without the defensive share
  the prediction misjudged the night street's LED-lit table: the optimized table's thin tails
  are what the share fills in.)
- the optimized candidate with the least prediction wins if it is below (1 − ``margin``) times
  the emission table's; otherwise the emission table stays. The margin (default 0.1) is there
  because the model is an approximation: in the benchmark's window room, tables predicted
  within 1 % of the emission table's error measured 4 % and 60 % worse (docs/guiding.md), while
  every table predicted to gain more than 10 % gained.

The chosen optimized tables are copied (byte for byte) into an output folder that
``pbrt --wavelength-guiding-tables`` reads; a mixture whose emission table wins has no file
there, so the renderer keeps its emission table (with a warning naming it). ``choice.csv``
beside them lists every table's predictions and choice.
"""
from __future__ import annotations

import csv
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from wavelength_pdf.evaluation import transfer

EMISSION = "emission"
CHOICE = "choice.csv"


@dataclass(frozen=True)
class TileMap:
    """``tiles.txt`` / ``tiles.csv`` (design §5.2): each tile's table."""

    tile: int
    #: The film's pixel bounds (x0, y0, x1, y1) the tiles cover.
    bounds: tuple[int, int, int, int]
    #: (tiles down, tiles across) table indices.
    index: np.ndarray

    def table_of(self, shape: tuple[int, int]) -> np.ndarray:
        """The table of each pixel of an image of ``shape`` (h, w) that spans the bounds (a
        rescaled render of the same film): the tile under each pixel's centre."""
        x0, y0, x1, y1 = self.bounds

        def tiles(n: int, extent: int, count: int) -> np.ndarray:  # pixel centres, from the bounds' corner
            return np.clip(((np.arange(n) + 0.5) * extent / n // self.tile).astype(int), 0, count - 1)

        h, w = shape
        return self.index[np.ix_(tiles(h, y1 - y0, self.index.shape[0]), tiles(w, x1 - x0, self.index.shape[1]))]


def read_tiles(path: str | Path) -> TileMap:
    """Read a guiding tile map; ValueError naming the file and line when it is not one."""
    import re

    path = Path(path)
    lines = path.read_text().splitlines()
    head = re.search(r"each tile of (\d+)x\1 pixels.*pixel bounds (-?\d+) (-?\d+) (-?\d+) (-?\d+)",
                     lines[0] if lines else "")
    if not head:
        raise ValueError(f"{path}:1: not a guiding tile map (its first line names the tile size and the "
                         "film's pixel bounds)")
    rows = []
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        try:
            rows.append([int(v) for v in line.split(",")])
        except ValueError:
            raise ValueError(f"{path}:{n}: not a row of table indices: {line[:60]!r}") from None
        if len(rows[-1]) != len(rows[0]) or min(rows[-1]) < 0:
            raise ValueError(f"{path}:{n}: {len(rows[-1])} tiles where the first row has {len(rows[0])}, "
                             "or a negative index")
    if not rows:
        raise ValueError(f"{path}: no tiles")
    tile, *bounds = (int(v) for v in head.groups())
    return TileMap(tile, tuple(bounds), np.asarray(rows, dtype=int))


def read_defensive(path: str | Path) -> tuple[np.ndarray, np.ndarray, float]:
    """``defensive.txt``: the defensive spectrum's wavelengths and values and its share S."""
    import re

    path = Path(path)
    text = path.read_text()
    share = re.search(r"^# defensive share (\S+)$", text, re.M)
    try:
        values = np.array([[float(v) for v in line.split()] for line in text.splitlines()
                           if line.strip() and not line.startswith("#")])
        S = float(share.group(1)) if share else float("nan")
    except ValueError:
        raise ValueError(f"{path}: not a defensive spectrum (lines 'lambda value')") from None
    if not (0 <= S < 1) or values.ndim != 2 or values.shape[1] != 2 or len(values) < 2:
        raise ValueError(f"{path}: not a defensive spectrum with a '# defensive share S' line")
    return values[:, 0], values[:, 1], S


def with_defensive(table, lam: np.ndarray, phi: np.ndarray, S: float):
    """``table`` as the renderer samples an optimized guiding table (design §1.8): each density
    (1 − S) p_k + S Φ̂ on the union of the two grids (each linear between its nodes, 0 outside)."""
    from wavelength_pdf.table import Table, normalize

    grid = np.union1d(np.asarray(table.grid, dtype=np.float64), lam)
    d = np.interp(grid, lam, phi, left=0.0, right=0.0)
    pdfs = np.stack([(1 - S) * np.interp(grid, table.grid, p, left=0.0, right=0.0) + S * d
                     for p in np.asarray(table.pdfs, dtype=np.float64)])
    return Table(grid, normalize(grid, pdfs), list(table.comments))


def cluster_rows(path: str | Path) -> list[dict[str, str]]:
    """The rows of a guiding cluster list (``clusters.txt`` beside the mixtures, ``clusters.csv``
    beside an image: design §5.2), its comment lines skipped."""
    with open(path, newline="") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def read_clusters(path: str | Path) -> dict[int, str]:
    """``clusters.txt``: each table's mixture name (``mixture-HASH``)."""
    path = Path(path)
    rows = cluster_rows(path)
    try:
        return {int(r["table"]): r["mixture"] for r in rows}
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{path}: not a guiding cluster list (columns table, tiles, mixture, shares)") from None


@dataclass(frozen=True)
class MixtureChoice:
    """One guiding table's candidates and the one chosen."""

    table: int
    mixture: str
    #: The transfer's lit pixels of this table the prediction is over (0: none; then the
    #: whole image's lit pixels stand in).
    pixels: int
    #: Candidate -> predicted mean squared CIEDE2000 of its wavelength sampling over the pixels
    #: (the path noise every candidate shares left out).
    predicted: dict[str, float]
    chosen: str


def choose_guiding_tables(scene: str | Path, spectra: str | Path, candidates: Mapping[str, str | Path],
                          spp: int, out: str | Path, workdir: str | Path, *,
                          margin: float = 0.1, pixel_sampler: str = "sobol", resolution: float = 0.5,
                          pbrt: Path | None = None, transfer_spp: int = transfer.SPP,
                          say: Callable[[str], None] = lambda m: None) -> list[MixtureChoice]:
    """Choose each guiding table's table among its emission table and ``candidates`` (name ->
    folder of ``mixture-HASH.csv``, as ``wavelength-pdf batch`` writes), write the chosen
    optimized ones and ``choice.csv`` to ``out`` (replaced whole, never left half written),
    and return the choices. Every input is read and checked before the renders."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.evaluation.choose import check_spp, wavelength_error
    from wavelength_pdf.spectra import read_spd
    from wavelength_pdf.table import read_table

    spectra, out = Path(spectra), Path(out)
    check_spp(spp, pixel_sampler)
    if not 0 <= margin < 1:
        raise ValueError(f"margin must lie in [0, 1), not {margin:g}")
    for name in ("clusters.txt", "tiles.txt", "defensive.txt"):
        if not (spectra / name).is_file():
            raise ValueError(f"{spectra}: no {name} (write the folder with pbrt --wavelength-guiding "
                             "--wavelength-guiding-spectra DIR at the render's settings)")
    if EMISSION in candidates:
        raise ValueError(f"{EMISSION!r} names the mixtures' own emission tables; name the candidates otherwise")
    for name, folder in candidates.items():
        if not Path(folder).is_dir():
            raise ValueError(f"{folder}: no such folder of tables (candidate {name!r})")
    if out.exists() and not (out.is_dir() and (not any(out.iterdir()) or (out / CHOICE).is_file())):
        raise ValueError(f"{out}: exists and is not an earlier choice's folder; give a new or empty folder")
    tiles = read_tiles(spectra / "tiles.txt")
    mixtures = read_clusters(spectra / "clusters.txt")
    if tiles.index.max() >= len(mixtures) or set(mixtures) != set(range(len(mixtures))):
        raise ValueError(f"{spectra}: tiles.txt and clusters.txt do not match (tables {sorted(mixtures)}, "
                         f"tile indices up to {tiles.index.max()})")
    lam, phi, S = read_defensive(spectra / "defensive.txt")
    lamps, tables = {}, {}
    for k, mix in mixtures.items():
        lamps[k] = read_spd(spectra / f"{mix}.spd", transfer.LO, transfer.HI)
        own = spectra / f"table-{k}.txt"
        emission = read_table(own) if own.is_file() else None
        if emission is None or not any(c.strip().startswith("source: stratified") for c in emission.comments):
            raise ValueError(f"{own}: missing or not an emission table (write the folder without "
                             "--wavelength-guiding-tables)")
        tables[k] = {EMISSION: emission}
        for name, folder in candidates.items():
            path = Path(folder) / f"{mix}.csv"
            if path.is_file():  # read (and refused) before any render
                tables[k][name] = with_defensive(read_table(path), lam, phi, S)
    if not any(len(t) > 1 for t in tables.values()):
        raise ValueError(f"none of the folders {', '.join(map(str, candidates.values()))} holds a table of "
                         f"these mixtures ({', '.join(sorted(mixtures.values()))})")

    say(f"choose-guiding: the scene's transfer ({transfer_spp} spp) and incoherence at {resolution:g} of its "
        f"size, in {workdir}")
    tr = transfer.of_file(scene, workdir, resolution, pbrt, transfer_spp)
    of_pixel = tiles.table_of(tr.mask.shape)[tr.mask]
    basis = P.hat_basis(tr.centres, transfer.LO, transfer.HI)
    choices = []
    for k, mix in sorted(mixtures.items()):
        pixels = of_pixel == k
        sel = pixels if pixels.any() else np.ones_like(pixels)
        predicted = {}
        for name, table in tables[k].items():
            say(f"choose-guiding: table {k} ({mix}), predicting {name}")
            predicted[name] = wavelength_error(table, lamps[k], basis, tr, spp, pixel_sampler, sel)
        best = min((n for n in predicted if n != EMISSION), key=predicted.get, default=EMISSION)
        chosen = best if predicted[best] < (1 - margin) * predicted[EMISSION] else EMISSION
        choices.append(MixtureChoice(k, mix, int(pixels.sum()), predicted, chosen))
    write_choice(out, choices, candidates)
    return choices


def write_choice(out: Path, choices: list[MixtureChoice], candidates: Mapping[str, str | Path]) -> None:
    """The chosen tables (copied from ``candidates``' folders) and choice.csv into ``out``, through a
    temporary folder beside it."""
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        names = sorted({n for c in choices for n in c.predicted})
        with open(tmp / CHOICE, "w", newline="") as f:
            f.write("# wavelength-pdf choose-guiding: each guiding table's predicted de2 (wavelength part, "
                    "mean over its pixels) per candidate; design section 6.8\n")
            w = csv.writer(f)
            w.writerow(["table", "mixture", "pixels", "chosen", *names])
            for c in choices:
                w.writerow([c.table, c.mixture, c.pixels, c.chosen,
                            *(f"{c.predicted[n]:.6g}" if n in c.predicted else "" for n in names)])
        for c in choices:
            if c.chosen != EMISSION:
                shutil.copyfile(Path(candidates[c.chosen]) / f"{c.mixture}.csv", tmp / f"{c.mixture}.csv")
        if out.exists():
            shutil.rmtree(out)
        tmp.rename(out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
