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
  pixel's incoherence and dispersed share, and one copy per kind of light (``kinds.txt``: the
  kinds' spectra E_j and their emitters; the other kinds' emitters dark) gives each pixel's
  transfer t_pj along that kind's own paths, so that the pixel's spectrum is
  sum_j E_j(λ) t_pj(λ) (:func:`.transfer.kind_transfers`). Without ``kinds.txt`` (a folder of
  an older renderer) a pixel of table k is modelled as lit by that table's mixture m_k along
  the whole transfer's paths, m_k(λ) t_p(λ): exact only when every kind reaches the pixel by
  the same paths, and in the benchmark's window room, where daylight and the tube light a
  pixel along different paths, it chose the wrong table on half of them (docs/guiding.md);
- each candidate is predicted as the renderer samples it: ``emission`` is the table that run
  wrote (``table-K.txt``: design §1.7's stratified table of the mixture with the defensive
  share), each folder's ``mixture-HASH.csv`` is mixed with the defensive spectrum
  (``defensive.txt``) as the renderer mixes it (design §1.8). The prediction is the mean over
  table k's pixels of :func:`wavelength_pdf.predict.pixel_de2`. (Without the defensive share
  the prediction misjudged the night street's LED-lit table: the optimized table's thin tails
  are what the share fills in.)
- with ``polish``, each mixture's emission table and each folder's table, polished for that
  table's pixels by the same prediction as an objective (:func:`.choose.polished_tables`), are
  candidates too; no folder is needed then (no optimizer run);
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
#: The renderer's wavelength range (its Lambda_min, Lambda_max), where it cuts the defensive
#: spectrum into bands.
RENDER_RANGE = (360.0, 830.0)


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


def defensive_bands(lam: np.ndarray, phi: np.ndarray):
    """The four equal-mass bands of the defensive spectrum Φ̂ that an optimized guiding table's
    four densities take their share of (design §1.8): §1.7's stratified table of Φ̂ on the
    renderer's 360-830 nm."""
    from wavelength_pdf.spectra import Spectrum
    from wavelength_pdf.stratified import stratified_table

    return stratified_table(Spectrum("defensive", "the scene's emission", lam, phi), "spd", *RENDER_RANGE)


def with_defensive(table, lam: np.ndarray, phi: np.ndarray, S: float):
    """``table`` as the renderer samples an optimized guiding table (design §1.8): each density
    (1 − S) p_k + S b_k, b_k the k-th of four equal-mass bands of the defensive spectrum Φ̂
    (§1.7's stratified table of Φ̂ on the renderer's 360-830 nm), on the union of the grids."""
    from wavelength_pdf.table import Table, normalize

    bands = defensive_bands(lam, phi)
    grid = np.union1d(np.asarray(table.grid, dtype=np.float64), bands.grid)
    pdfs = np.stack([(1 - S) * np.interp(grid, table.grid, p, left=0.0, right=0.0)
                     + S * np.interp(grid, bands.grid, b, left=0.0, right=0.0)
                     for p, b in zip(np.asarray(table.pdfs, dtype=np.float64), np.asarray(bands.pdfs))])
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


def read_kinds(path: str | Path) -> tuple[list, list[set[tuple[str, int]]]]:
    """``kinds.txt`` (design §5.2): each kind of light's spectrum and its emitters, as
    (file name, line) pairs that :func:`.transfer.kind_transfers` leaves lit. ValueError naming
    the file and line when it is not one."""
    from wavelength_pdf.spectra import check_support, make_spectrum

    path = Path(path)
    lines = path.read_text().splitlines()
    spectra: list[list[tuple[float, float]]] = []
    lights: list[set[tuple[str, int]]] = []
    table = False
    for n, line in enumerate(lines, start=1):
        text = line.strip()
        try:
            if text.startswith("# kind "):
                if int(text.split()[2]) != len(spectra):
                    raise ValueError("kinds out of order")
                spectra.append([])
                lights.append(set())
            elif not text or text.startswith("#"):
                continue
            elif text == "kind,light":
                table = True
            elif table:
                kind, label = text.split(",", 1)
                file, line_no, _col = label.rsplit(":", 2)
                lights[int(kind)].add((Path(file).name, int(line_no)))
            else:
                lam, value = (float(v) for v in text.split())
                spectra[-1].append((lam, value))
        except (ValueError, IndexError):
            raise ValueError(f"{path}:{n}: not a line of a guiding kinds file: {line[:60]!r}") from None
    if not spectra or not table or any(not s for s in spectra) or any(not l for l in lights):
        raise ValueError(f"{path}: not a guiding kinds file (each kind's '# kind K' spectrum, then "
                         "'kind,light' rows naming every kind's lights)")
    out = []
    for k, pairs in enumerate(spectra):
        lam, val = np.asarray(pairs).T
        sp = make_spectrum(f"kind-{k}", f"{path} kind {k}", lam, val, where=str(path))
        check_support(sp, transfer.LO, transfer.HI, where=f"{path}: kind {k}")
        out.append(sp)
    return out, lights


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
                          pbrt: Path | None = None, transfer_spp: int = transfer.SPP, polish: bool = False,
                          polish_evaluations: int | None = None,
                          say: Callable[[str], None] = lambda m: None) -> list[MixtureChoice]:
    """Choose each guiding table's table among its emission table and ``candidates`` (name ->
    folder of ``mixture-HASH.csv``, as ``wavelength-pdf batch`` writes), write the chosen
    optimized ones and ``choice.csv`` to ``out`` (replaced whole, never left half written),
    and return the choices. Every input is read and checked before the renders.

    ``polish``: also each mixture's emission table and each candidate's table polished for the
    pixels of its guiding table (:func:`.choose.polished_tables`, each at most ``polish_evaluations``
    evaluations, None: its default), named "polished NAME"; a chosen one is written as it was
    polished, and the renderer mixes the defensive share into it as into any table it reads."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.evaluation.choose import POLISHED, check_spp, polished_tables, wavelength_error
    from wavelength_pdf.spectra import read_spd
    from wavelength_pdf.table import read_table

    spectra, out = Path(spectra), Path(out)
    check_spp(spp, pixel_sampler)
    if polish and pixel_sampler != "sobol":
        raise ValueError("the polish models the low-discrepancy pixel sampler's strata (design §4.6), "
                         f"not the {pixel_sampler} sampler")
    if not 0 <= margin < 1:
        raise ValueError(f"margin must lie in [0, 1), not {margin:g}")
    for name in ("clusters.txt", "tiles.txt", "defensive.txt"):
        if not (spectra / name).is_file():
            raise ValueError(f"{spectra}: no {name} (write the folder with pbrt --wavelength-guiding "
                             "--wavelength-guiding-spectra DIR at the render's settings)")
    if not candidates and not polish:
        raise ValueError("nothing to choose from: give folders of optimized tables, or polish")
    if EMISSION in candidates:
        raise ValueError(f"{EMISSION!r} names the mixtures' own emission tables; name the candidates otherwise")
    if polish and any(n.startswith(f"{POLISHED} ") for n in candidates):
        raise ValueError(f"'{POLISHED} NAME' names the polished tables; name the candidates otherwise")
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
    # tables: as the renderer samples them (the prediction's); given: as read (the polish's starts,
    # and what is written out: the renderer mixes the defensive share into what it reads)
    lamps, tables, given = {}, {}, {}
    for k, mix in mixtures.items():
        lamps[k] = read_spd(spectra / f"{mix}.spd", transfer.LO, transfer.HI)
        own = spectra / f"table-{k}.txt"
        emission = read_table(own) if own.is_file() else None
        if emission is None or not any(c.strip().startswith("source: stratified") for c in emission.comments):
            raise ValueError(f"{own}: missing or not an emission table (write the folder without "
                             "--wavelength-guiding-tables)")
        tables[k], given[k] = {EMISSION: emission}, {EMISSION: emission}
        for name, folder in candidates.items():
            path = Path(folder) / f"{mix}.csv"
            if path.is_file():  # read (and refused) before any render
                given[k][name] = read_table(path)
                tables[k][name] = with_defensive(given[k][name], lam, phi, S)
    if candidates and not any(len(t) > 1 for t in tables.values()):
        raise ValueError(f"none of the folders {', '.join(map(str, candidates.values()))} holds a table of "
                         f"these mixtures ({', '.join(sorted(mixtures.values()))})")

    kind_spectra, kind_lights = read_kinds(spectra / "kinds.txt") if (spectra / "kinds.txt").is_file() else ([], [])

    say(f"choose-guiding: the scene's transfer ({transfer_spp} spp) and incoherence at {resolution:g} of its "
        f"size, in {workdir}")
    tr = transfer.of_file(scene, workdir, resolution, pbrt, transfer_spp)
    kinds = None
    if len(kind_spectra) > 1:
        say(f"choose-guiding: each of the {len(kind_spectra)} kinds of light's transfer ({transfer_spp} spp)")
        kinds = transfer.kind_transfers(scene, workdir, kind_lights, tr, resolution, pbrt, transfer_spp)
    elif not kind_spectra:
        say("choose-guiding: no kinds.txt (an older renderer's folder): each pixel lit by its table's mixture")
    of_pixel = tiles.table_of(tr.mask.shape)[tr.mask]
    share = (S, defensive_bands(lam, phi))  # the same for every table's polish
    basis = P.hat_basis(tr.centres, transfer.LO, transfer.HI)
    choices = []
    for k, mix in sorted(mixtures.items()):
        pixels = of_pixel == k
        sel = pixels if pixels.any() else np.ones_like(pixels)
        if polish:
            for name, table in polished_tables(lamps[k] if kinds is None else kind_spectra, tr, spp, given[k], say,
                                               pixels=sel, kinds=kinds, as_sampled=tables[k],
                                               share=share,
                                               max_evaluations=polish_evaluations,
                                               what=f"table {k} ({mix})'s pixels").items():
                given[k][name] = table
                tables[k][name] = with_defensive(table, lam, phi, S)
        predicted = {}
        for name, table in tables[k].items():
            say(f"choose-guiding: table {k} ({mix}), predicting {name}")
            predicted[name] = wavelength_error(table, lamps[k] if kinds is None else kind_spectra, basis, tr, spp,
                                               pixel_sampler, sel, kinds)
        best = min((n for n in predicted if n != EMISSION), key=predicted.get, default=EMISSION)
        chosen = best if predicted[best] < (1 - margin) * predicted[EMISSION] else EMISSION
        choices.append(MixtureChoice(k, mix, int(pixels.sum()), predicted, chosen))
    write_choice(out, choices, {c.table: Path(candidates[c.chosen]) / f"{c.mixture}.csv" if c.chosen in candidates
                                else given[c.table][c.chosen] for c in choices if c.chosen != EMISSION})
    return choices


def write_choice(out: Path, choices: list[MixtureChoice], chosen: Mapping[int, object]) -> None:
    """The chosen tables (``chosen``: table index -> a candidate's file, copied byte for byte, or
    a polished Table) and choice.csv into ``out``, through a temporary folder beside it."""
    from wavelength_pdf.table import write_table

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
            if c.chosen == EMISSION:
                continue
            if isinstance(chosen[c.table], (str, Path)):
                shutil.copyfile(chosen[c.table], tmp / f"{c.mixture}.csv")
            else:
                write_table(tmp / f"{c.mixture}.csv", chosen[c.table])
        if out.exists():
            shutil.rmtree(out)
        tmp.rename(out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
