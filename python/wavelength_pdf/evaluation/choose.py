"""Which table for this scene? Each candidate's image error, predicted from three renders of
the scene (design §6.8), without rendering with any of them.

The candidates are the given tables and the simple samplers of design §1.7 for the scene's
lamp (``uniform``, ``visible``, ``spd``, ``luminance``, ``xyz``), and with ``polish`` the
``spd`` table and each given one polished for the scene's pixels (:func:`for_image`, design
§4.6). For each, the prediction is
the mean over the scene's lit pixels of the linearised squared CIEDE2000 of the pixel's mean
of N samples, with each pixel's own light, incoherence and dispersion
(:func:`wavelength_pdf.predict.pixel_de2`), plus the path noise all candidates share
(:func:`wavelength_pdf.predict.path_de2`). Over the benchmark's scene sweep it ranks the
samplers at 0.91-0.95 (Spearman) and its choice was never worse than the best simple
sampler by more than 10 % (docs/benchmark.md, "Each pixel's own light").
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from wavelength_pdf.evaluation import transfer

@dataclass(frozen=True)
class Prediction:
    """One candidate's predicted image error (mean over lit pixels, squared CIEDE2000)."""

    name: str
    table: object
    #: The wavelength sampling's part, the candidate's own.
    wavelength: float
    #: The path noise, the same for every candidate.
    path: float

    @property
    def total(self) -> float:
        return self.wavelength + self.path


def simple_tables(spectrum) -> dict[str, object]:
    """The simple samplers' tables for ``spectrum`` over the transfer's range, named as
    :data:`wavelength_pdf.stratified.METHODS` (the benchmark's names, design §1.7, §6.7)."""
    from wavelength_pdf import stratified

    out = {"uniform": stratified.uniform_table(transfer.LO, transfer.HI), "visible": stratified.visible_table()}
    for w in stratified.WEIGHTS:
        out[w] = stratified.stratified_table(spectrum, w, transfer.LO, transfer.HI)
    return out


def check_spp(spp: int, pixel_sampler: str) -> None:
    """ValueError unless the prediction models ``spp`` with ``pixel_sampler``."""
    from wavelength_pdf import predict as P

    if spp < 1:
        raise ValueError(f"spp must be at least 1, not {spp}")
    if pixel_sampler not in P.PIXEL_SAMPLERS:
        raise ValueError(f"pixel sampler must be one of {P.PIXEL_SAMPLERS}, not {pixel_sampler!r}")
    if pixel_sampler == "sobol" and P.U_POINTS % spp:
        raise ValueError(f"spp {spp} is not a power of two up to {P.U_POINTS}: the low-discrepancy sampler's "
                         "strata are modelled at powers of two (use --pixel-sampler independent otherwise)")


def side_by_side(tr: transfer.Transfer, kinds: np.ndarray | None, pixels: np.ndarray | slice = slice(None)):
    """The transfers of ``tr``'s pixels (those ``pixels`` selects), or with ``kinds`` (J, P, B)
    each kind's side by side, (P, J B): the coefficients of the stacked kinds' bases."""
    return tr.t[pixels] if kinds is None else np.concatenate(list(np.asarray(kinds)[:, pixels]), axis=1)


def wavelength_error(table, spectrum, basis, tr: transfer.Transfer, spp: int, pixel_sampler: str = "sobol",
                     pixels: np.ndarray | slice = slice(None), kinds: np.ndarray | None = None) -> float:
    """The mean over ``tr``'s lit pixels (or those ``pixels`` selects) of each pixel's predicted
    squared CIEDE2000 of its wavelength sampling with ``table`` under ``spectrum``
    (:func:`wavelength_pdf.predict.pixel_de2`, with its incoherence and dispersion).

    ``spectrum`` may be a list of J kinds of light with ``kinds`` (J, P, B) their transfers
    (:func:`.transfer.kind_transfers`): each pixel is then lit by every kind along that kind's
    own paths, sum_j E_j t_pj, each sample carrying one kind's light
    (:func:`wavelength_pdf.predict.kinds_spread`); ``tr``'s spread, where it has one, counts
    for one kind of light. Where ``tr`` has the spread's cells (images rendered with ``pbrt
    --wavelength-net``, :func:`.transfer.of_file`), the part of the spread between them counts
    as stratified (:func:`wavelength_pdf.predict.pixel_de2`)."""
    from wavelength_pdf import predict as P

    spectra = list(spectrum) if isinstance(spectrum, (list, tuple)) else [spectrum]
    if kinds is None and len(spectra) > 1:
        raise ValueError("several kinds of light need their transfers (kinds)")
    t = side_by_side(tr, kinds, pixels)
    pc = P.stack_path_colours([P.basis_path_colours(table, sp, basis) for sp in spectra])
    one = P.one_wavelength_covariance(table, spectra, basis)
    r = tr.incoherence[pixels]
    if kinds is not None:
        spread = P.kinds_spread(t, pc.target[:, 1], np.repeat(np.arange(len(spectra)), len(basis.labels)), r)
        cells = None
    else:
        spread, cells = tr.spread_at(pixels)
    return float(np.mean(P.pixel_de2(pc, t, spp, pixel_sampler, incoherence=r, terminated=tr.terminated[pixels],
                                     one_wavelength=one, spread=spread, cells=cells)))


#: The prefix of a polished candidate's name: "polished spd" is the ``spd`` table polished.
POLISHED = "polished"
#: Below this spp :func:`for_image` also polishes each start at this spp first and then at the
#: one asked for ("polished spd via 64 spp"). At 16 spp the polish from J's table stopped in a
#: worse basin than the table polished at 64 spp, by the prediction at 16 spp itself and in the
#: renders (docs/benchmark.md, "The table for the image at each spp, and on the Cornell
#: box"). Why the higher spp's objective leads to the better basin is not measured.
CONTINUATION_SPP = 64


def polished_tables(spectrum, tr: transfer.Transfer, spp: int, tables: Mapping[str, object],
                    say: Callable[[str], None] = lambda m: None, *, pixels: np.ndarray | slice = slice(None),
                    kinds: np.ndarray | None = None, as_sampled: Mapping[str, object] | None = None,
                    share: tuple[float, object] | None = None, max_evaluations: int | None = None,
                    what: str = "the scene's pixels") -> dict[str, object]:
    """Each of ``tables`` polished for ``tr``'s pixels (those ``pixels`` selects) at ``spp`` by
    the ``pixels`` objective (:func:`wavelength_pdf.optimize.optimize_for_pixels`, design §4.6:
    the low-discrepancy pixel sampler's strata, with ``tr``'s spread and its cells where it has
    them), named
    "polished NAME". ``spectrum`` may be a list of kinds of light with ``kinds`` (J, P, B) their
    transfers, each pixel lit by every kind along its own paths (as :func:`wavelength_error`;
    with their spread). ``share``: (S, D), each table polished as it is sampled with the share S
    of table D's densities mixed in (a guiding table's defensive share, design §1.8).
    ``max_evaluations``: each polish's budget (None: its default).

    A polish never comes out worse than its table by the objective, but which table it starts
    from matters: it is a local search, and the lamp's emission table and J's table sit in
    different basins (docs/benchmark.md, "A pixel's spread": from the emission table it wins
    under FL7 and LED-B4, J's table stays better under FL11 and high-pressure sodium), so the
    caller predicts every polish and keeps the best. A table the health rule refuses (biased, or
    of infinite variance: a lamp dark over part of the range) is polished as ``as_sampled``
    holds it where it has one (guiding's table with the renderer's defensive share in), else not
    polished (said); it is still predicted as given."""
    from wavelength_pdf.optimize import optimize_for_pixels

    t = side_by_side(tr, kinds, pixels)
    spread, cells = tr.spread_at(pixels) if kinds is None else (None, None)
    budget = {} if max_evaluations is None else {"max_evaluations": max_evaluations}
    out = {}
    for name, table in tables.items():
        say(f"choose: polishing {name} for {what} at {spp} spp")
        sampled = (as_sampled or {}).get(name)
        for start in [table] + ([sampled] if sampled is not None and sampled is not table else []):
            try:
                out[f"{POLISHED} {name}"] = optimize_for_pixels(
                    spectrum, start, t, tr.centres, spp, incoherence=tr.incoherence[pixels],
                    terminated=tr.terminated[pixels], spread=spread, cells=cells, share=share, **budget).table
                break
            except ValueError as e:
                say(f"choose: {name} not polished{' as sampled' if start is not table else ''}: {e}")
    return out


def rank(spectrum, tr: transfer.Transfer, cands: Mapping[str, object], spp: int, pixel_sampler: str = "sobol",
         say: Callable[[str], None] = lambda m: None) -> list[Prediction]:
    """Every candidate's predicted error in the scene ``tr`` is the transfer of, best first."""
    from wavelength_pdf import predict as P

    basis = P.hat_basis(tr.centres, transfer.LO, transfer.HI)
    out, path = [], None
    for name, table in cands.items():
        say(f"choose: predicting {name}")
        w = wavelength_error(table, spectrum, basis, tr, spp, pixel_sampler)
        if path is None:
            pc = P.basis_path_colours(table, spectrum, basis)
            path = float(np.mean(P.path_de2(tr.t @ pc.target, tr.incoherence, spp)))
        out.append(Prediction(name, table, w, path))
    return sorted(out, key=lambda p: p.wavelength)


def candidates(spectrum, tables: Mapping[str, object], simple: bool = True) -> dict[str, object]:
    """The simple samplers' tables (with ``simple``) and the given ones (renamed "NAME (given)"
    where a simple sampler has the name)."""
    cands = dict(simple_tables(spectrum)) if simple else {}
    for name, table in tables.items():
        cands[name if name not in cands else f"{name} (given)"] = table
    return cands


def for_image(spectrum, tr: transfer.Transfer, spp: int, tables: Mapping[str, object] | None = None, *,
              simple: bool = True, polish: bool = True, pixel_sampler: str = "sobol",
              polish_evaluations: int | None = None,
              say: Callable[[str], None] = lambda m: None) -> list[Prediction]:
    """The table for the image ``tr`` is the transfer of, at ``spp``: the simple samplers
    (``simple``) and ``tables``, with ``polish`` also the ``spd`` table and each of ``tables``
    polished for the scene's pixels (:func:`polished_tables`, each at most
    ``polish_evaluations`` evaluations, None: its default; below :data:`CONTINUATION_SPP`
    each also polished at that spp first, then at ``spp``), all ranked by their predicted
    error (:func:`rank`), best first. Without ``tables`` this needs no optimizer run but the
    polish (seconds). The polish models the low-discrepancy pixel sampler."""
    check_spp(spp, pixel_sampler)
    cands = candidates(spectrum, tables or {}, simple)
    if polish:
        if pixel_sampler != "sobol":
            raise ValueError("the polish models the low-discrepancy pixel sampler's strata (design §4.6), "
                             f"not the {pixel_sampler} sampler")
        from wavelength_pdf.stratified import METHODS

        starts = {"spd": cands["spd"] if "spd" in cands else simple_tables(spectrum)["spd"],
                  **{n: t for n, t in cands.items() if n not in METHODS}}
        polish_options = {"say": say, "max_evaluations": polish_evaluations}
        cands.update(polished_tables(spectrum, tr, spp, starts, **polish_options))
        if spp < CONTINUATION_SPP:
            first = polished_tables(spectrum, tr, CONTINUATION_SPP, starts, **polish_options)
            cands.update(polished_tables(spectrum, tr, spp, {
                f"{name.removeprefix(POLISHED + ' ')} via {CONTINUATION_SPP} spp": t for name, t in first.items()},
                **polish_options))
    if not cands:
        raise ValueError("no table to predict: give tables or keep the simple samplers")
    return rank(spectrum, tr, cands, spp, pixel_sampler, say)


def predict_tables(scene: str | Path, tables: Mapping[str, object], spp: int, workdir: str | Path, *,
                   pixel_sampler: str = "sobol", resolution: float | tuple[int, int] = 0.1,
                   pbrt: Path | None = None, transfer_spp: int = transfer.SPP, simple: bool = True,
                   polish: bool = False, spread: bool = False, net: bool = False,
                   polish_evaluations: int | None = None,
                   say: Callable[[str], None] = lambda m: None) -> list[Prediction]:
    """Every candidate's predicted error in ``scene`` at ``spp``, best first.

    ``scene`` must be lit by one kind of light (its emitters' spectra equal up to scale);
    ``tables`` maps names to :class:`~wavelength_pdf.table.Table`; ``simple`` adds the simple
    samplers, ``polish`` the polished tables of :func:`for_image` (each at most
    ``polish_evaluations`` evaluations, None: its default). ``spread``: each pixel's
    spread (:func:`.transfer.spread`, the spectra its samples see) in place of its
    incoherence; it is a property of the pixels you render, so give ``resolution`` 1 (the
    scene's own film) or the size you render at; with ``net`` (you render with ``pbrt
    --wavelength-net``) the part of it that the net stratifies counts as stratified. The renders
    go to ``workdir`` and are kept while the scene and the renderer are unchanged."""
    if net and not spread:
        raise ValueError("net models the spread's cells: give spread too")
    check_spp(spp, pixel_sampler)
    spectrum = transfer.one_kind(scene)
    if not (simple or tables or polish):
        raise ValueError("no table to predict: give tables or keep the simple samplers")
    size = resolution if isinstance(resolution, tuple) else f"{resolution:g} of its size"
    say(f"choose: the scene's transfer ({transfer_spp} spp) and incoherence (2 x {transfer.INCOHERENCE_SPP} spp) "
        f"at {size}" + (", with each pixel's spread" if spread else "") + f", in {workdir}")
    tr = transfer.of_file(scene, workdir, resolution, pbrt, transfer_spp, with_spread=spread, net=net)
    return for_image(spectrum, tr, spp, tables, simple=simple, polish=polish, pixel_sampler=pixel_sampler,
                     polish_evaluations=polish_evaluations, say=say)
