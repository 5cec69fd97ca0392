"""Each pixel's spectrum under any lamp, from one render of the scene (design §6.8).

A scene lit by one kind of lamp (every emitter's spectrum the same up to scale; pbrt-v4
normalizes each to the same luminance whatever its shape) sends to pixel p the radiance
E(λ) G_p(λ) / Y(E): G_p is what the scene's light paths do to the light (reflection, filtering,
exposure) and does not depend on the lamp. One render under a flat lamp with a spectral film
gives G_p at the film's bucket centres; with G_p linear between them
(:func:`wavelength_pdf.predict.hat_basis`), the pixel's colour and the noise of its estimate
are known for every lamp and table without rendering again
(:func:`wavelength_pdf.predict.pixel_de2`). Two more renders of the same copy, a seed pair,
measure each pixel's incoherence (how much its paths' magnitude varies from sample to
sample); the spectral film's channel ``wavelengths.terminated`` gives each pixel's share of
light that kept one wavelength (dispersion). ``wavelength-pdf choose`` and the benchmark's
prediction (``predict_benchmark.py --colours pixels``) use this.

Units: the coefficients are scaled so that t_p · (the basis' colours under a lamp) is the
pixel's XYZ in the image's own units (Lab relative to D65 at Y = 1, as the benchmark's
measures): one scale per scene, the ratio of the render's own luminance (its RGB) to the
buckets' (sums over the lit pixels), which absorbs the film's sensor, exposure and pbrt-v4's
normalization of spectra. Scenes with lamps of several kinds are not separable so (their
pixel spectra are sums of differently shaped lamps) and are refused.
"""
from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Collection, Sequence

import numpy as np

from wavelength_pdf.exr import read_spectral
from wavelength_pdf.spectra import Spectrum

#: The spectral film's buckets over the benchmark's range (20 nm each): surface colours and
#: filters are smooth at that scale; the lamp's own lines come from its spectrum, not the film.
BUCKETS = 20
#: Samples per pixel of the transfer render (one per scene).
SPP = 1024
#: Samples per pixel of each of the two renders that measure a pixel's incoherence (the
#: relative variance of its paths' magnitude from one sample to the next), and their
#: wavelengths per path (``--wavelength-repeats``: so that the flat lamp's own wavelength
#: noise does not count as the paths').
INCOHERENCE_SPP = 64
INCOHERENCE_REPEATS = 8
LO, HI = 380.0, 780.0

#: The spectral film's channel of the share of light that kept one wavelength (design §6.8).
TERMINATED = "wavelengths.terminated"

FLAT = Spectrum("flat", "equal energy", np.array([LO, HI]), np.array([1.0, 1.0]))


@dataclass(frozen=True)
class Transfer:
    """A scene's pixels as coefficients of the hat basis (lit pixels only)."""

    #: Bucket centres, nm (B,).
    centres: np.ndarray
    #: (P, B): pixel p's spectrum under the flat lamp at the centres, in image units.
    t: np.ndarray
    #: (h, w) mask of the pixels in ``t`` (``measures.lit_pixels`` of the flat render).
    mask: np.ndarray
    #: The luminance scale applied (render RGB / buckets).
    scale: float
    #: (P,): each pixel's incoherence r_p (:func:`wavelength_pdf.predict.pixel_de2`), from a
    #: seed pair of renders at n spp: n (Y_1 - Y_2)^2 / 2 over the pixel's Y^2 (unbiased per
    #: pixel, noisy; only means over many pixels are meant).
    incoherence: np.ndarray
    #: (P,): each pixel's share of light carried by paths that kept one wavelength (a
    #: dispersive surface), the spectral film's channel ``wavelengths.terminated``.
    terminated: np.ndarray
    #: (P, B, B) or None: each pixel's spread (:func:`spread`), the covariance of the
    #: spectra its samples see, in the units of ``t``.
    spread: np.ndarray | None = None
    #: None, or for each (i, j) of :func:`net_cells` ((i, j), (P, B, B)): the part of the
    #: spread that lies between the pixel's 2^i x 2^j cells of equal filter weight (along y and
    #: x; :func:`cell_spread_of`), some of which ``pbrt --wavelength-net`` stratifies
    #: (:func:`wavelength_pdf.predict.pixel_de2`).
    cells: tuple[tuple[tuple[int, int], np.ndarray], ...] | None = None

    def spread_at(self, pixels: np.ndarray | slice = slice(None)):
        """(spread, cells) of the pixels ``pixels`` selects, each None where not measured."""
        return (None if self.spread is None else self.spread[pixels],
                None if self.cells is None else tuple((g, c[pixels]) for g, c in self.cells))


#: The renders that measure each pixel's spread (:func:`spread`) cut each side of a pixel into
#: this many sub-pixels, at SPREAD_SPP samples each (one path per sub-pixel, so that their
#: product is each path's own: as many paths per pixel as the incoherence renders).
SPREAD_FACTOR = 8
SPREAD_SPP = 1
#: Wavelengths per path of the spread's renders (``--wavelength-repeats``, each 4 wavelengths,
#: shifted by k/K): each path's spectrum over the 20 buckets is one factor of the spread's
#: products, and its wavelength noise, though it cancels in expectation, makes a pixel's spread
#: indefinite. On the benchmark's ColorChecker (32 x 24, 8 x 8 sub-pixels) the median share of
#: a pixel's absolute eigenvalue mass that is negative: 0.32 at 8 repeats (0.31 with four seeds
#: averaged at 8, the same cost as 32), 0.052 at 32, 0.014 at 64, 0.001 at 256 (docs/benchmark.md,
#: "A spread without negative variance"). Each render costs about K / 8 times that at 8.
SPREAD_REPEATS = 64
#: A pixel's filter footprint is cut into 2^i x 2^j cells of equal filter weight, i, j up to
#: this, and the spread between them measured apart (:func:`net_cells`, :func:`cell_spread_of`):
#: ``pbrt --wavelength-net`` draws u together with the film position, so a cell's samples have
#: stratified u among themselves (design §5.2, §6.8). 2^NET_LEVEL is SPREAD_FACTOR: the finest
#: cells are the sub-pixels, whose one path each is not told apart from the cell.
NET_LEVEL = SPREAD_FACTOR.bit_length() - 1


def net_cells(level: int = NET_LEVEL) -> tuple[tuple[int, int], ...]:
    """The (i, j) whose spread between 2^i x 2^j cells is measured: every pair up to ``level``
    but (0, 0) (the pixel itself: none) and (level, level) (the sub-pixels: the spread itself)."""
    return tuple((i, j) for i in range(level + 1) for j in range(level + 1) if 0 < i + j < 2 * level)


#: The pixel filters the spread models, with pbrt-v4's default radius of each (pixels).
FILTER_RADII = {"gaussian": 1.5, "box": 0.5, "triangle": 2.0}


def _unmodelled(kind: str) -> str:
    return (f"pixel filter {kind!r} is not modelled ({', '.join(FILTER_RADII)}): its negative lobes give "
            "samples negative weights")


def filter_shares(n: int, factor: int, kind: str = "gaussian", radius: float = 1.5,
                  sigma: float = 0.5) -> np.ndarray:
    """(n, n * factor): along one axis of a film of ``n`` pixels, the share of pixel i's
    samples that fall in each of the ``factor`` times finer sub-pixels. pbrt-v4 draws a
    pixel's film positions with a density proportional to its filter (filter importance
    sampling, every weight then 1 for these filters), here the ``kind`` pbrt-v4 names
    ``gaussian`` (exp(-x^2 / 2 sigma^2) less its value at the radius), ``box`` or
    ``triangle``, of ``radius`` pixels, taken at each sub-pixel's centre. Written here: it
    is pbrt-v4's filter definitions, which no library serves."""
    if kind not in FILTER_RADII:
        raise ValueError(_unmodelled(kind))
    if not (n >= 1 and factor >= 1 and radius > 0 and sigma > 0):
        raise ValueError(f"filter_shares needs n, factor >= 1 and radius, sigma > 0, got {n}, {factor}, "
                         f"{radius}, {sigma}")
    d = ((np.arange(n * factor) + 0.5)[None, :] / factor - (np.arange(n) + 0.5)[:, None])
    if kind == "gaussian":
        f = np.exp(-d ** 2 / (2 * sigma ** 2)) - np.exp(-radius ** 2 / (2 * sigma ** 2))
    elif kind == "triangle":
        f = radius - np.abs(d)
    else:
        f = np.ones_like(d)
    f = np.where(np.abs(d) < radius, np.maximum(f, 0.0), 0.0)
    total = f.sum(axis=1, keepdims=True)
    if np.any(total <= 0):
        raise ValueError(f"a {kind} filter of radius {radius:g} covers no sub-pixel's centre at {factor} per pixel")
    return f / total


def pixel_filter(scene_file: Path) -> tuple[str, float, float, float]:
    """The scene's PixelFilter as (kind, x radius, y radius, sigma), with pbrt-v4's defaults
    (a gaussian of radius 1.5 and sigma 0.5 when there is none; a box of radius 0.5; a
    triangle of radius 2); ValueError naming the file and line for a filter
    :func:`filter_shares` does not model or a parameter that is not a number."""
    from wavelength_pdf.pbrt_syntax import split_params, statements, tokenize

    scene_file = Path(scene_file)
    sts = [split_params(st, 1) for st in statements(tokenize(scene_file.read_text(), scene_file))
           if st.directive.text == "PixelFilter"]
    if not sts:
        return "gaussian", 1.5, 1.5, 0.5
    st = sts[-1]
    kind = st.args[0].text
    values = {}
    for p in st.params:
        try:
            values[p.name] = float(p.values[0].text)
        except (IndexError, ValueError):
            raise ValueError(f"{p.where}: PixelFilter parameter \"{p.name}\" is not a number") from None
    if kind not in FILTER_RADII:
        raise ValueError(f"{st.directive.where}: {_unmodelled(kind)}")
    r0 = FILTER_RADII[kind]
    return kind, values.get("xradius", r0), values.get("yradius", r0), values.get("sigma", 0.5)


def spread_of(a: np.ndarray, b: np.ndarray, shares_y: np.ndarray, shares_x: np.ndarray) -> np.ndarray:
    """(h, w, B, B): each pixel's spread from two renders ``a``, ``b`` (H, W, B) of its
    sub-pixels, H = h * k, W = w * k, whose wavelength noises are independent: the covariance
    over the pixel's samples of the spectrum each sees, sum_q w_q (T_q - T)(T_q - T)' with
    w_q the pixel's shares of its samples (:func:`filter_shares`, (h, H) and (w, W)). One
    factor of each product comes from each render, so that their noise cancels in expectation
    (unbiased, however noisy; only means over many pixels are meant). From two seeds, T_q is
    each sub-pixel's mean spectrum; from one seed at two wavelength seeds and one path per
    sub-pixel (:func:`spread`), each path's own, and the mean's product, taken from the same
    paths, then counts sum_q w_q^2 of that covariance (about 1 % at 8 sub-pixels a side)."""
    if a.shape != b.shape or a.ndim != 3 or shares_y.shape[1] != a.shape[0] or shares_x.shape[1] != a.shape[1]:
        raise ValueError(f"spread_of: renders {a.shape} and {b.shape} against shares {shares_y.shape}, "
                         f"{shares_x.shape}")

    from scipy.sparse import csr_array

    # A share reaches a few pixels' radius: as sparse matrices, a product costs the image's size.
    sy, sx = csr_array(shares_y), csr_array(shares_x)
    return _weighted_spread(a, b, lambda img: np.asarray((sx @ (sy @ img).T).T))


def _weighted_spread(a: np.ndarray, b: np.ndarray, pixel_mean) -> np.ndarray:
    """(h, w, B, B): each pixel's sum_q w_q (a_q - a)(b_q - b)', symmetrised, of two images
    (.., .., B) of spectra a_q, b_q, ``pixel_mean`` mapping one band of an image (2-D) to each
    pixel's weighted mean (h, w) with weights w_q summing to 1 (a, b the pixel's means). The
    sum :func:`spread_of` (sub-pixels) and :func:`cell_spread_of` (cells) share; a band pair
    at a time, since all products of an image's bands at 8 sub-pixels a side would not fit."""
    B = a.shape[2]
    ma = np.stack([pixel_mean(a[..., i]) for i in range(B)], axis=-1)
    mb = np.stack([pixel_mean(b[..., i]) for i in range(B)], axis=-1)
    out = np.empty(ma.shape[:2] + (B, B))
    for i in range(B):
        for j in range(i, B):
            v = 0.5 * (pixel_mean(a[..., i] * b[..., j] + a[..., j] * b[..., i]) - ma[..., i] * mb[..., j]
                       - ma[..., j] * mb[..., i])
            out[..., i, j] = out[..., j, i] = v
    return out


def cell_shares(shares: np.ndarray, g: int) -> np.ndarray:
    """(n g, N): along one axis, each pixel's shares (:func:`filter_shares`, (n, N)) cut into
    ``g`` cells of equal filter weight: row i g + k holds the shares of pixel i's sub-pixels in
    its cell k, a sub-pixel going whole to the cell of its centre's place in the pixel's
    cumulative share (pbrt-v4 maps a sample's film numbers to the filter's offset monotonically,
    one axis at a time for these separable filters, so cell k of [0, 1) is the k-th g-quantile
    of the filter's weight)."""
    if g < 1:
        raise ValueError(f"cells per side must be >= 1, not {g}")
    n, N = shares.shape
    middle = np.cumsum(shares, axis=1) - shares / 2
    cell = np.minimum((middle * g).astype(int), g - 1)
    out = np.zeros((n * g, N))
    out[np.arange(n)[:, None] * g + cell, np.arange(N)[None, :]] = shares
    return out


def cell_spread_of(a: np.ndarray, b: np.ndarray, shares_y: np.ndarray, shares_x: np.ndarray,
                   cells: tuple[int, int], spread: np.ndarray, correct: bool = False) -> np.ndarray:
    """(h, w, B, B): the part of each pixel's ``spread`` (:func:`spread_of` of the same renders)
    that lies between its gy x gx cells of equal filter weight (``cells``, along y and x;
    :func:`cell_shares`): the covariance of the cells' mean spectra, sum_c W_c (T_c - T)(T_c - T)'.

    As measured (the default), the levels nest: over the renders' paths, a cell's spread
    from the pixel is the sum of its parts (design §6.8), none negative in expectation. Where
    the paths within a cell differ at random (one off a red wall, the next off a green one),
    the cells' means are noisy themselves and the measure counts that spread, W = S - B, over
    the cell's effective number of paths k_c (W_c^2 / sum_q w_q^2) too: with the gaussian
    filter at least 36 paths per cell at the levels the net stratifies at 64 spp, so a few per
    cent of W. ``correct`` takes it off: with 1/k = sum_c W_c / k_c over the pixel's cells,
    sigma = sum_q w_q^2 (the pixel mean's own share, which the measured spread
    S' = B + (1 - sigma) W lacks too, :func:`spread_of`) and rho = (1/k - sigma) / (1 - sigma),
    B = (B' - rho S') / (1 - rho), unbiased where the paths within a cell are random draws but
    not where a cell's sub-pixels differ by a fixed edge. On the ColorChecker the two differ by
    a few per cent of the spread at any level. One factor of each product from each render, as
    in :func:`spread_of`."""
    from scipy.sparse import csr_array

    h, w, B = shares_y.shape[0], shares_x.shape[0], a.shape[2]
    if spread.shape != (h, w, B, B):
        raise ValueError(f"cell_spread_of: spread {spread.shape} against {h} x {w} pixels of {B} buckets")
    gy, gx = cells
    cy, cx = cell_shares(shares_y, gy), cell_shares(shares_x, gx)
    Cy, Cx = csr_array(cy), csr_array(cx)

    def cellsum(img, my=Cy, mx=Cx):  # (h gy, w gx): each cell's weighted sum
        return np.asarray((mx @ (my @ img).T).T)

    def per_pixel(x):  # (h gy, w gx, ...) summed over each pixel's cells
        return x.reshape(h, gy, w, gx, *x.shape[2:]).sum(axis=(1, 3))

    ones = np.ones(a.shape[:2])
    weight = cellsum(ones)
    inv = np.divide(1.0, weight, out=np.zeros_like(weight), where=weight > 0)
    ma = np.stack([cellsum(a[..., i]) * inv for i in range(B)], axis=-1)
    mb = np.stack([cellsum(b[..., i]) * inv for i in range(B)], axis=-1)
    prod = _weighted_spread(ma, mb, lambda x: per_pixel(weight * x))
    if not correct:
        return prod
    squares = cellsum(ones, csr_array(cy ** 2), csr_array(cx ** 2))
    inv_k, sigma = per_pixel(squares * inv), per_pixel(squares)
    rho = ((inv_k - sigma) / np.maximum(1.0 - sigma, 1e-12))[..., None, None]
    return (prod - rho * spread) / np.maximum(1.0 - rho, 1e-12)


def _spread_renders(source, folder, size, pbrt, nthreads, factor, spp, repeats=SPREAD_REPEATS, seed=1):
    """The two renders of :func:`spread` (H, W, B) and the pixel filter's shares along y and x
    (named by their repeats and seed, so that a folder's renders at others are not taken)."""
    w, h = size
    copy = copy_scene(source, folder, (w * factor, h * factor))
    kind, rx, ry, sigma = pixel_filter(copy)
    a, b = (read_spectral(render(copy, pbrt, spp, nthreads, seed=seed, repeats=repeats, wavelength_seed=ws,
                                 name=f"spread-wavelengths{ws}-repeats{repeats}-seed{seed}.exr"))[1]
            for ws in (1, 2))
    return a, b, filter_shares(h, factor, kind, ry, sigma), filter_shares(w, factor, kind, rx, sigma)


def spread(source: str | Path, folder: str | Path, size: tuple[int, int], pbrt: Path | None = None,
           nthreads: int | None = None, factor: int = SPREAD_FACTOR, spp: int = SPREAD_SPP,
           repeats: int = SPREAD_REPEATS, seed: int = 1) -> np.ndarray:
    """(h, w, B, B): the spread of every pixel of ``source`` rendered at ``size`` (w, h)
    under the flat lamp (:func:`spread_of`), in bucket units, from two renders of a copy at
    ``factor`` times the resolution (``folder``; kept while the scene and the renderer are
    unchanged) with the scene's own pixel filter (:func:`pixel_filter`): the same paths
    (``--seed 1``) at independent wavelengths (``--wavelength-seed`` 1 and 2, design §5.2).

    A pixel's paths see different spectra, T = t + D: where they reach different surfaces (a
    patch's edge, a texture finer than a pixel), and where one path reaches the lamp off a
    red wall and the next off a green one. The part D of each sample's estimate is not
    stratified by the pixel's u, and adds sum_bc S_bc Cov_u(C_b, C_c) / N, S the spread
    (:func:`wavelength_pdf.predict.pixel_de2`). With ``spp`` 1 each sub-pixel is one path and
    S is the paths' own covariance; with more, that of their means in a sub-pixel. ``repeats``
    wavelengths per path (:data:`SPREAD_REPEATS`) set how much of S's noise is each path's
    wavelength noise; ``seed`` (``--seed``) draws other paths."""
    return spread_of(*_spread_renders(source, folder, size, pbrt, nthreads, factor, spp, repeats, seed))


def negative_share(spread: np.ndarray, pooled: bool = False) -> np.ndarray | float:
    """(...,): each pixel's share of its spread's absolute eigenvalue mass that is negative (0
    for a covariance; what noise adds, :data:`SPREAD_REPEATS`), nan where the spread is 0; with
    ``pooled``, the pixels' negative mass over their absolute mass, summed over all of them (the
    share of the noise where the spread is large, as a prediction summed over pixels weighs it)."""
    ev = np.linalg.eigvalsh(spread)
    negative, mass = np.clip(-ev, 0, None).sum(axis=-1), np.abs(ev).sum(axis=-1)
    if pooled:
        total = float(mass.sum())
        return float(negative.sum()) / total if total > 0 else float("nan")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(mass > 0, negative / mass, np.nan)


def spread_with_cells(source: str | Path, folder: str | Path, size: tuple[int, int], pbrt: Path | None = None,
                      nthreads: int | None = None, cells: Sequence[tuple[int, int]] = net_cells(),
                      repeats: int = SPREAD_REPEATS):
    """:func:`spread` and, from the same renders, for each (i, j) of ``cells``
    ((i, j), (h, w, B, B)), the part of it that lies between the pixel's 2^i x 2^j cells
    (:func:`cell_spread_of`)."""
    a, b, sy, sx = _spread_renders(source, folder, size, pbrt, nthreads, SPREAD_FACTOR, SPREAD_SPP, repeats)
    S = spread_of(a, b, sy, sx)
    return S, tuple(((i, j), cell_spread_of(a, b, sy, sx, (2 ** i, 2 ** j), S)) for i, j in cells)


def _spectral_film(text: str, path: Path, buckets: int, lo: float, hi: float,
                   size: tuple[int, int]) -> str:
    """``text`` with its Film statement made a spectral film of ``buckets`` over [lo, hi]; a
    scene without one (pbrt-v4's default film) gets one of ``size`` before its WorldBegin."""
    from wavelength_pdf.pbrt_syntax import split_params, statements, tokenize

    sts = list(statements(tokenize(text, path)))
    films = [split_params(st, 1) for st in sts if st.directive.text == "Film"]
    spectral = (f'"spectral" "integer nbuckets" [ {buckets} ] "float lambdamin" [ {lo:g} ] '
                f'"float lambdamax" [ {hi:g} ]')
    if len(films) > 1:
        raise ValueError(f"{path}: {len(films)} Film statements (lines "
                         f"{', '.join(str(f.directive.line) for f in films)}); a scene has one")
    if films:
        arg = films[0].args[0]
        return text[:arg.start] + spectral + text[arg.end:]
    world = next((st for st in sts if st.directive.text == "WorldBegin"), None)
    if world is None:
        raise ValueError(f"{path}: no Film statement and no WorldBegin to put one before")
    film = f'Film {spectral} "integer xresolution" [ {size[0]} ] "integer yresolution" [ {size[1]} ]\n'
    return text[:world.directive.start] + film + text[world.directive.start:]


def one_kind(source: str | Path):
    """The spectrum of the one kind of light that lights ``source`` (its emitters' spectra all
    the same up to scale), cut to [LO, HI]; ValueError naming them when there are several, or
    when an emitter has no lamp spectrum (RGB, an image: its light is of another kind)."""
    import warnings

    from wavelength_pdf.scene_spectra import NotOptimizableWarning, scene_spectra

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NotOptimizableWarning)
        kinds = scene_spectra(source, LO, HI)
    other = [w for w in caught if issubclass(w.category, NotOptimizableWarning)]
    if other:
        raise ValueError(f"{str(other[0].message).split(': not optimizable')[0]}: an emitter without a lamp "
                         "spectrum, whose light is not of the scene's one kind")
    if len(kinds) > 1:
        raise ValueError(f"{source}: lit by {len(kinds)} kinds of light ({', '.join(k.name for k in kinds)}), "
                         "whose pixel spectra are not one lamp times the scene's transfer")
    return kinds[0]


def copy_scene(source: str | Path, folder: str | Path, resolution: tuple[int, int] | float | None = None,
               buckets: int = BUCKETS, dark: Collection[tuple[str, int]] = ()) -> Path:
    """``folder/scene.pbrt``: a copy of ``source`` whose every emitter has a flat spectrum over
    [LO, HI] and whose film is a spectral film of ``buckets``, at ``resolution`` (design §6.1's
    scene copy). Its transfer holds for the scene relit by any one lamp (as the benchmark's
    jobs are); for the scene's own lamps, only when they are of one kind
    (:func:`one_kind`). ``dark``: emitters (file name, line) left dark in the copy
    (:func:`kind_transfers`)."""
    from wavelength_pdf.evaluation.render import temporary
    from wavelength_pdf.evaluation.scene_edit import DEFAULT_FILM, edit_scene

    source, folder = Path(source), Path(folder)
    # A draft of its own and an atomic write: two processes may copy one scene at once.
    draft = edit_scene(source, FLAT, temporary(folder / "draft.pbrt"), lo=LO, hi=HI, resolution=resolution,
                       pixel_sampler="sobol", dark=dark)
    size = resolution if isinstance(resolution, tuple) else \
        tuple(max(1, round(v * (resolution or 1.0))) for v in DEFAULT_FILM)
    try:
        text = _spectral_film(draft.read_text(), draft, buckets, LO, HI, size)
    finally:
        draft.unlink()
    path = folder / "scene.pbrt"
    if not path.is_file() or path.read_text() != text:  # unchanged: its renders stay valid
        tmp = temporary(path)
        tmp.write_text(text)
        os.replace(tmp, path)
    return path


def render(scene_file: Path, pbrt: Path | None = None, spp: int = SPP, nthreads: int | None = None,
           seed: int = 0, repeats: int = 1, name: str = "transfer.exr",
           wavelength_seed: int | None = None) -> Path:
    """Render the transfer scene to ``name`` beside it (once: an image newer than the scene
    and the renderer is kept), with ``wavelength_seed`` as ``--wavelength-seed``."""
    from wavelength_pdf.evaluation.render import temporary
    from wavelength_pdf.renderer import find_pbrt

    exr = scene_file.with_name(name)
    binary = find_pbrt(pbrt)
    if exr.is_file() and exr.stat().st_mtime >= max(scene_file.stat().st_mtime, binary.stat().st_mtime):
        return exr  # made from this scene by this renderer
    tmp = temporary(exr)  # of its own, as copy_scene's: two processes may render one image at once
    cmd = [str(binary), "--quiet", "--spp", str(spp), "--seed", str(seed), "--outfile", str(tmp),
           *(["--wavelength-repeats", str(repeats)] if repeats > 1 else []),
           *(["--wavelength-seed", str(wavelength_seed)] if wavelength_seed is not None else []),
           *(["--nthreads", str(nthreads)] if nthreads else []), str(scene_file)]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0 or not tmp.is_file():
        tmp.unlink(missing_ok=True)
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {done.returncode}):\n{done.stderr.strip()}")
    tmp.replace(exr)
    return exr


def load(exr: Path, pair: tuple[Path, Path] | None = None, pair_spp: int = INCOHERENCE_SPP) -> Transfer:
    """The transfer of a rendered scene (:func:`render`), scaled to the image's units, with
    each pixel's incoherence from a seed ``pair`` of renders at ``pair_spp`` (None: 0)."""
    from wavelength_pdf import predict as P
    from wavelength_pdf.evaluation.benchmark.measures import lit_pixels
    from wavelength_pdf.evaluation.metrics import rgb_to_xyz
    from wavelength_pdf.exr import read_channel, read_rgb, read_spectral

    centres, buckets = read_spectral(exr)
    rgb = read_rgb(exr)
    mask = lit_pixels(rgb)
    t = np.clip(buckets[mask], 0.0, None)
    flat = P.path_colours(_uniform_table(), FLAT, P.hat_basis(centres, LO, HI), points=2 ** 10)
    y_buckets = float(np.sum(t @ flat.target[:, 1]))
    y_rgb = float(np.sum(rgb_to_xyz(rgb[mask])[:, 1]))
    if not (y_buckets > 0 and y_rgb > 0):
        raise ValueError(f"{exr}: no light in the lit pixels (luminance {y_rgb:g}, buckets {y_buckets:g})")
    scale = y_rgb / y_buckets
    r = np.zeros(t.shape[0])
    if pair is not None:
        y = rgb_to_xyz(rgb[mask])[:, 1]
        y1, y2 = (rgb_to_xyz(read_rgb(p)[mask])[:, 1] for p in pair)
        r = np.zeros_like(y)
        np.divide(pair_spp * (y1 - y2) ** 2 / 2.0, y * y, out=r, where=y > 0)
    return Transfer(centres, t * scale, mask, scale, r, read_channel(exr, TERMINATED)[mask])


def _uniform_table():
    from wavelength_pdf.stratified import uniform_table

    return uniform_table(LO, HI)


def of_file(source: str | Path, folder: str | Path, resolution: tuple[int, int] | float | None = None,
            pbrt: Path | None = None, spp: int = SPP, nthreads: int | None = None,
            with_spread: bool = False, net: bool = False) -> Transfer:
    """Copy (:func:`copy_scene`), render (once: kept while the scene and the renderer are
    unchanged) and load the transfer of a scene, with its incoherence, and with
    ``with_spread`` each pixel's spread (:func:`spread`, its renders in ``folder/spread``);
    with ``net`` too (for images rendered with ``pbrt --wavelength-net``) its parts between
    the cells of :func:`net_cells` (:func:`spread_with_cells`)."""
    scene_file = copy_scene(source, folder, resolution)
    if with_spread:
        pixel_filter(scene_file)  # a filter the spread does not model is refused before any render
    pair = tuple(render(scene_file, pbrt, INCOHERENCE_SPP, nthreads, seed=seed, repeats=INCOHERENCE_REPEATS,
                        name=f"incoherence-seed{seed}.exr") for seed in (1, 2))
    tr = load(render(scene_file, pbrt, spp, nthreads), pair)
    if not with_spread:
        return tr
    h, w = tr.mask.shape
    S, cells = spread_with_cells(source, Path(folder) / "spread", (w, h), pbrt, nthreads,
                                 net_cells() if net else ())
    return replace(tr, spread=S[tr.mask] * tr.scale ** 2,
                   cells=tuple((g, c[tr.mask] * tr.scale ** 2) for g, c in cells) if net else None)


def kind_transfers(source: str | Path, folder: str | Path, lights: Sequence[Collection[tuple[str, int]]],
                   whole: Transfer, resolution: tuple[int, int] | float | None = None,
                   pbrt: Path | None = None, spp: int = SPP, nthreads: int | None = None) -> np.ndarray:
    """Each kind of light's share of every pixel's transfer, for a scene lit by several kinds
    (design §6.8): ``lights[j]`` names kind j's emitters (file name, line); the copy of kind j
    has every other emitter dark. Returns (J, P, B): kind j's transfer of ``whole``'s lit
    pixels, in ``whole``'s units (the same film, so its scale), so that the kinds sum to
    ``whole.t`` up to the renders' noise. A pixel lit by kind j alone is E_j(λ) t_j(λ); lit by
    several, sum_j E_j(λ) t_j(λ), each kind along its own paths."""
    from wavelength_pdf.exr import read_spectral

    names = {n for kind in lights for n in kind}
    out = []
    for j in range(len(lights)):
        scene_file = copy_scene(source, Path(folder) / f"kind-{j}", resolution, dark=names - set(lights[j]))
        centres, buckets = read_spectral(render(scene_file, pbrt, spp, nthreads))
        if not np.allclose(centres, whole.centres) or buckets.shape[:2] != whole.mask.shape:
            raise ValueError(f"{scene_file}: its film differs from the whole scene's copy")
        out.append(np.clip(buckets[whole.mask], 0.0, None) * whole.scale)
    return np.stack(out)
