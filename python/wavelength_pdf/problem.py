"""The objective's data for one lamp spectrum on one table grid (design §4): :class:`Problem`.

The spectrum is used at its own resolution and the CMFs at theirs (1 nm), both linear
between their nodes, so f = I * (xbar, ybar, zbar) is piecewise quadratic on the union of
spectrum, CMF and table nodes: the problem holds every function on that union, scaled so
that the target c (the exact integral of f over the grid range) has Y = 1.

All arrays that describe a problem are padded to a multiple of ``_PAD`` entries, so the
jitted functions compile once per size class rather than once per spectrum.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import jax
import jax.numpy as jnp
import numpy as np

from . import aot, colorimetry
from .precision import float64
from .model import (DEFAULT_GRID, check_objective_nodes, check_table_nodes, normalize_density, product_integrals,
                    trapezoid)

#: Width (nm) of the ramp that stands in for the jump of a spectrum that stops at a
#: non-zero value inside the table range (its effect on any integral is ~1e-12 relative).
_JUMP_RAMP_NM = 1e-9

#: Node arrays are padded to a multiple of this many entries (fewer distinct jit shapes).
#: The work per evaluation grows with the padded size: a smooth lamp's search problem has
#: 170-185 nodes, which a multiple of 64 pads to 192 and one of 256 to 256 (a third more
#: time per evaluation, measured); a finer step would mean more size classes to compile.
_PAD = 64

#: Spectra with more than ``SPECTRUM_MAX_SAMPLES`` samples (a line written on a 0.01 nm
#: list) drop the samples that linear interpolation between the kept ones reproduces to
#: ``SPECTRUM_TOL`` of the peak (runs of zeros, straight stretches, far tails of lines):
#: J changes by ~1e-9 relative, the work per evaluation can drop a hundredfold. Smaller
#: spectra are used exactly as given.
SPECTRUM_TOL = 1e-9
SPECTRUM_MAX_SAMPLES = 2000


@dataclass(frozen=True)
class Problem:
    """Everything the objective needs about one spectrum on one table grid.

    Attributes
    ----------
    name, source : str
        The spectrum's name and where it came from.
    grid : (M+1,) float64 array, nm
        Table nodes.
    nodes : (Nf,) float64 array, nm
        Union of spectrum, CMF and table nodes inside [grid[0], grid[-1]] (first
        ``n_nodes`` entries; the rest is padding beyond grid[-1] with zero values).
    spec : (Nf,) float64 array
        Spectrum at ``nodes``, scaled so that the target has Y = 1.
    cmf : (Nf, 3) float64 array
        xbar, ybar, zbar at ``nodes``.
    n_nodes : int
        Number of real entries of ``nodes``.
    c : (3,) float64 array
        Target XYZ (exact integral of f over the grid range), Y = 1.
    lab_c : (3,) float64 array
        Lab of the target (D65 white, Y = 1).
    scale : float
        Factor that took the spectrum's values to the scaled ``spec``.
    weights : (K,) float64 array or None
        With a set of surface reflectances (design §4.5): the weight of each colour in J
        (summing to 1); None for the white surface of §4.1.
    refl : (K, Nf) float64 array or None
        The reflectances at ``nodes``. With them, ``spec`` is still the lamp alone (scaled
        so that the white surface's colour has Y = 1, as without reflectances), ``c`` and
        ``lab_c`` are per colour, (K, 3), and the arrays the jitted functions see carry
        ``spec`` per colour, (K, Nf): I * R_k at the nodes.
    reflectance_set : str
        The set's name ('' without reflectances).
    objective, spp : str, int
        The objective the value "J" of every evaluation stands for (design §4.6): ``"J"``
        (§4.1) or ``"stratified"`` for a pixel of ``spp`` stratified samples; set by
        :func:`with_objective`, which adds the arrays it reads.
    """

    name: str
    source: str
    grid: np.ndarray
    nodes: np.ndarray
    spec: np.ndarray
    cmf: np.ndarray
    n_nodes: int
    c: np.ndarray
    lab_c: np.ndarray
    scale: float
    arrays: dict = field(repr=False, compare=False, default_factory=dict)
    weights: np.ndarray | None = None
    refl: np.ndarray | None = None
    reflectance_set: str = ""
    objective: str = "J"
    spp: int = 1
    #: The ``pixels`` objective's weights (3, K*3, K*3) over the surface colours (a hat basis
    #: of a scene's pixel spectra): :func:`wavelength_pdf.predict.pixel_weights`.
    pixels: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def batched(self) -> bool:
        """Whether J is the weighted mean over a set of surface colours (design §4.5)."""
        return self.weights is not None


def _with_ramps(wl: np.ndarray, val: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes of a piecewise-linear function that is zero outside [wl[0], wl[-1]].

    A function that starts or ends at a non-zero value jumps there; a ramp of width
    ``_JUMP_RAMP_NM`` to zero makes it continuous without changing it measurably.
    """
    wl = np.asarray(wl, dtype=np.float64)
    val = np.asarray(val, dtype=np.float64)
    if val[0] != 0.0:
        wl = np.concatenate([[wl[0] - _JUMP_RAMP_NM], wl])
        val = np.concatenate([[0.0], val])
    if val[-1] != 0.0:
        wl = np.concatenate([wl, [wl[-1] + _JUMP_RAMP_NM]])
        val = np.concatenate([val, [0.0]])
    return wl, val


def _pad_to(n: int) -> int:
    return ((n + _PAD - 1) // _PAD) * _PAD


def _exact_integral(nodes: np.ndarray, spec: np.ndarray, cmf: np.ndarray) -> np.ndarray:
    """Integral of spec * cmf over the node range; exact (Simpson) for the product of two
    functions linear on every node interval."""
    return np.sum(product_integrals(nodes, spec[:-1], spec[1:], cmf), axis=0)


def make_problem(spectrum, grid: np.ndarray = DEFAULT_GRID, reflectances=None) -> Problem:
    """Build the objective's data for ``spectrum`` on the table ``grid``.

    Parameters
    ----------
    spectrum : wavelength_pdf.spectra.Spectrum
        Any object with ``wavelengths`` (nm, increasing), ``values`` (>= 0), ``name`` and
        ``source``; linear between samples and zero outside them.
    grid : (M+1,) array, nm
        Strictly increasing table nodes.
    reflectances : wavelength_pdf.reflectances.ReflectanceSet, optional
        Surface colours (design §4.5): J becomes the weighted mean over them of J with
        f = I * R_k * cmf. Each reflectance is linear between its own samples and keeps its
        end values beyond them; its samples join the union of nodes, and I * R_k is taken
        linear between the union's nodes (the form in which the estimator and its target
        both see it, so the target stays the estimator's exact mean).

    Raises
    ------
    ValueError
        If the grid is not strictly increasing or the spectrum has no power that the
        CMFs see inside the grid range.
    """
    grid = np.asarray(grid, dtype=np.float64)
    source = getattr(spectrum, "source", "<spectrum>")
    name = getattr(spectrum, "name", source)
    if grid.ndim != 1 or grid.size < 2 or not np.all(np.diff(grid) > 0):
        raise ValueError(f"{source}: the table grid must be strictly increasing with >= 2 nodes")
    wl = np.asarray(spectrum.wavelengths, dtype=np.float64)
    val = np.asarray(spectrum.values, dtype=np.float64)
    if wl.ndim != 1 or wl.shape != val.shape or wl.size < 2:
        raise ValueError(f"{source}: wavelengths and values must be 1-D of equal length >= 2")
    if not (np.all(np.isfinite(wl)) and np.all(np.isfinite(val))):
        raise ValueError(f"{source}: spectrum contains NaN or infinity")
    if np.any(val < 0):
        raise ValueError(f"{source}: spectrum has negative values")
    if not np.all(np.diff(wl) > 0):
        raise ValueError(f"{source}: spectrum wavelengths are not strictly increasing")
    lo, hi = float(grid[0]), float(grid[-1])
    check_table_nodes(grid.size, f"{source}: the table grid")
    if wl.size > SPECTRUM_MAX_SAMPLES and np.max(val) > 0:
        wl, val = _thin_spectrum(wl, val, SPECTRUM_TOL * np.max(val))

    # Union of all nodes inside the range, then every function evaluated on it exactly.
    swl, sval = _with_ramps(wl, val)
    cwl, cval = colorimetry.cmfs()
    cwl_r = np.concatenate([[cwl[0] - _JUMP_RAMP_NM], cwl, [cwl[-1] + _JUMP_RAMP_NM]])
    cval_r = np.concatenate([np.zeros((1, 3)), cval, np.zeros((1, 3))])
    parts = [swl, cwl_r, grid]
    if reflectances is not None:
        rwl = np.asarray(reflectances.wavelengths, dtype=np.float64)
        parts.append(rwl[(rwl > lo) & (rwl < hi)])
    nodes = np.unique(np.concatenate(parts))
    nodes = nodes[(nodes >= lo) & (nodes <= hi)]
    check_objective_nodes(nodes.size, grid.size, source)
    spec = np.interp(nodes, swl, sval, left=0.0, right=0.0)
    cmf = np.stack([np.interp(nodes, cwl_r, cval_r[:, i], left=0.0, right=0.0) for i in range(3)], axis=1)
    if reflectances is None:
        return _from_nodes(name, source, grid, nodes, spec, cmf)
    refl = np.stack([np.interp(nodes, rwl, r) for r in np.asarray(reflectances.values, dtype=np.float64)])
    return _from_nodes(name, source, grid, nodes, spec, cmf, refl=refl,
                       weights=np.asarray(reflectances.weights, dtype=np.float64),
                       reflectance_set=reflectances.name)


def _from_nodes(name: str, source: str, grid: np.ndarray, nodes: np.ndarray, spec: np.ndarray,
                cmf: np.ndarray, refl: np.ndarray | None = None, weights: np.ndarray | None = None,
                reflectance_set: str = "") -> Problem:
    """Problem from the spectrum and CMFs (and reflectances, (K, n)) given at the union
    nodes (inside the range)."""
    lo, hi = float(grid[0]), float(grid[-1])
    # Scale: first to a maximum of 1 (so that 1e-30 or 1e30 spectra behave alike), then
    # so that the exact target has Y = 1.
    peak = float(np.max(spec))
    if not peak > 0:
        raise ValueError(f"{source}: spectrum is zero over the table range {lo:g}-{hi:g} nm")
    spec = spec / peak
    c = _exact_integral(nodes, spec, cmf)
    if not c[1] > 0:
        raise ValueError(f"{source}: spectrum has no luminance (Y = 0) over {lo:g}-{hi:g} nm")
    spec = spec / c[1]
    scale = 1.0 / (peak * c[1])
    c = _exact_integral(nodes, spec, cmf)
    c = c / c[1]  # Y exactly 1
    if refl is None:
        spec_arr = spec
        lab_c = np.asarray(_xyz_to_lab_jit(c))
    else:
        # Each colour relative to the white surface under the same lamp (Y = 1), in Lab
        # relative to D65 at Y = 1 (design §4.5).
        spec_arr = spec[None, :] * refl
        c = np.stack([_exact_integral(nodes, s, cmf) for s in spec_arr])
        if not np.all(c[:, 1] > 0):
            k = int(np.flatnonzero(~(c[:, 1] > 0))[0])
            raise ValueError(f"{source}: surface colour #{k} of {reflectance_set!r} reflects "
                             f"nothing of this lamp (Y = 0) over {lo:g}-{hi:g} nm")
        lab_c = np.asarray(colorimetry.xyz_to_lab(c))

    # Padding: node arrays continue past hi (never reached) with zero values.
    n_nodes = nodes.size
    n_pad = _pad_to(n_nodes)
    extra = n_pad - n_nodes
    nodes_p = np.concatenate([nodes, hi + 1.0 + np.arange(extra, dtype=np.float64)])
    spec_p = np.concatenate([spec, np.zeros(extra)])
    cmf_p = np.concatenate([cmf, np.zeros((extra, 3))])
    spec_arr_p = np.concatenate([spec_arr, np.zeros(spec_arr.shape[:-1] + (extra,))], axis=-1)
    # Breakpoint wavelengths (padded with hi: duplicates give empty u-pieces) and their
    # table segments, fixed for the problem.
    bp = np.concatenate([nodes, np.full(extra, hi)])
    m = grid.size - 1
    bp_seg = np.clip(np.searchsorted(grid, bp, side="right") - 1, 0, m - 1)
    bp_t = bp - grid[bp_seg]
    bp_idx = np.concatenate([np.arange(n_nodes), np.full(extra, n_nodes - 1)])
    # Table segment that holds the node interval [nodes[n], nodes[n+1]].
    node_tseg = np.clip(np.searchsorted(grid, nodes_p, side="right") - 1, 0, m - 1)

    arrays = {
        "grid": np.asarray(grid),
        "nodes": np.asarray(nodes_p),
        "spec": np.asarray(spec_arr_p),
        "cmf": np.asarray(cmf_p),
        "bp": np.asarray(bp),
        "bp_seg": np.asarray(bp_seg),
        "bp_t": np.asarray(bp_t),
        "bp_idx": np.asarray(bp_idx),
        "node_tseg": np.asarray(node_tseg),
        "lab_c": np.asarray(lab_c),
        "c": np.asarray(c),
    }
    refl_p = None
    if refl is not None:
        w = np.asarray(weights, dtype=np.float64)
        arrays["weights"] = np.asarray(w / w.sum())
        refl_p = np.concatenate([refl, np.zeros((refl.shape[0], extra))], axis=1)
    # One transfer, not jnp.asarray per array (each compiles a staging function per
    # shape outside a trace: a dozen compilations per process).
    arrays = jax.device_put(arrays)
    return Problem(
        name=name, source=source, grid=grid, nodes=nodes_p, spec=spec_p, cmf=cmf_p,
        n_nodes=n_nodes, c=c, lab_c=lab_c, scale=scale, arrays=arrays,
        weights=None if refl is None else np.asarray(arrays["weights"]), refl=refl_p,
        reflectance_set=reflectance_set,
    )


def _polyline_keep(x: np.ndarray, Y: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """Nodes to keep so that every column of Y, linearly interpolated between kept nodes,
    stays within tol of its values (Ramer-Douglas-Peucker, vertical distance)."""
    keep = np.zeros(x.size, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, x.size - 1)]
    while stack:
        a, b = stack.pop()
        if b <= a + 1:
            continue
        t = (x[a + 1 : b] - x[a]) / (x[b] - x[a])
        err = np.max(np.abs(Y[a + 1 : b] - (Y[a] + (Y[b] - Y[a]) * t[:, None])) / tol, axis=1)
        i = int(np.argmax(err))
        if err[i] > 1.0:
            m = a + 1 + i
            keep[m] = True
            stack += [(a, m), (m, b)]
    return keep


def _thin_spectrum(wl: np.ndarray, val: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples of a piecewise-linear spectrum that reproduce it within ``tol``: first the
    inside of runs of equal values goes (exact), then Ramer-Douglas-Peucker."""
    same = np.zeros(wl.size, dtype=bool)
    same[1:-1] = (val[1:-1] == val[:-2]) & (val[1:-1] == val[2:])
    wl, val = wl[~same], val[~same]
    keep = _polyline_keep(wl, val[:, None], np.array([tol]))
    return wl[keep], val[keep]


def simplify(problem: Problem, rel_tol: float) -> Problem:
    """A cheaper problem for searching: the spectrum and the CMFs on fewer nodes.

    Nodes are dropped while the spectrum and every CMF channel, interpolated linearly over
    the remaining nodes, stay within ``rel_tol`` of their maxima (table nodes are kept).
    J of a table changes by about rel_tol (relative) on the lamps tried; the solvers search
    on it and judge the result on the exact problem.
    """
    if rel_tol <= 0:
        return problem
    n = problem.n_nodes
    x = problem.nodes[:n]
    cols = [problem.spec[:n, None], problem.cmf[:n]]
    if problem.batched:
        cols.append(problem.refl[:, :n].T)
    Y = np.column_stack(cols)
    tol = rel_tol * np.maximum(np.max(Y, axis=0), 1e-300)
    keep = _polyline_keep(x, Y, tol) | np.isin(x, problem.grid)
    if not problem.batched:
        simpler = _from_nodes(problem.name, problem.source, problem.grid, x[keep], Y[keep, 0], Y[keep, 1:4])
    else:
        simpler = _from_nodes(problem.name, problem.source, problem.grid, x[keep], Y[keep, 0], Y[keep, 1:4],
                              refl=Y[keep, 4:].T, weights=problem.weights,
                              reflectance_set=problem.reflectance_set)
    return with_objective(simpler, problem.objective, problem.spp, problem.pixels)


def white_of(problem: Problem) -> Problem:
    """The same lamp on the same grid and nodes without surface colours (§4.1's white
    surface), for J."""
    n = problem.n_nodes
    white = _from_nodes(problem.name, problem.source, problem.grid, problem.nodes[:n], problem.spec[:n],
                        problem.cmf[:n])
    if SHARE in problem.arrays:
        white.arrays.update({k: problem.arrays[k] for k in (SHARE, SHARED)})
    return white


#: The arrays of :func:`with_share`: the share S and the four densities (4, M+1) it takes.
SHARE, SHARED = "share", "shared_pdfs"


def with_share(problem: Problem, share: float, pdfs: np.ndarray) -> Problem:
    """The same problem for a table that is sampled with a fixed share ``share`` of four given
    densities ``pdfs`` (4, M+1) on the problem's grid mixed into its own four, density k as
    (1 − S) p_k + S d_k, p_k and d_k each normalized: a guiding table with the renderer's
    defensive share (design §1.8). Every evaluation (the objective, its gradient, the health
    figures) sees the table so mixed, so that an optimizer makes the best table *as it will be
    sampled*; the table it returns is the unmixed p, which the renderer mixes as it reads it."""
    pdfs = np.asarray(pdfs, dtype=np.float64)
    if not 0 <= share < 1:
        raise ValueError(f"the share must lie in [0, 1), not {share:g}")
    if pdfs.shape != (4, problem.grid.size) or not np.all(np.isfinite(pdfs)) or np.any(pdfs < 0):
        raise ValueError(f"the shared densities must be 4 finite non-negative rows on the grid's "
                         f"{problem.grid.size} nodes, not {pdfs.shape}")
    if np.any(trapezoid(problem.grid, pdfs) <= 0):
        raise ValueError("a shared density has no mass on the problem's grid")
    arrays = dict(problem.arrays)
    arrays.update(jax.device_put({SHARE: np.float64(share), SHARED: normalize_density(problem.grid, pdfs)}))
    return replace(problem, arrays=arrays)


#: The objectives a problem can stand for (design §4.6).
OBJECTIVES = ("J", "stratified", "pixels")
#: The pixel's sample count ``stratified`` models unless told (the benchmark's middle spp).
DEFAULT_OBJECTIVE_SPP = 64
#: Most strata ``stratified`` models (each adds a breakpoint to every evaluation).
MAX_OBJECTIVE_SPP = 4096
#: Step of the finite differences that take CIEDE2000's local quadratic form (Lab is ~100:
#: small against any colour difference, large against rounding).
_METRIC_STEP = 1e-3


@float64
def de2000_metric(lab_c: np.ndarray) -> np.ndarray:
    """G (..., 3, 3) with CIEDE2000(lab_c + e, lab_c)^2 ~ e' G e for small e at each colour of
    ``lab_c`` (..., 3): the local quadratic form, by central differences of the squared
    difference (symmetric in +-e, as CIEDE2000's mean chroma makes it slightly odd). Not by
    automatic differentiation: CIEDE2000 has a square root with a cone point at e = 0.
    Always in float64: in float32 the differences of Lab ~100 over a step of 1e-3 lose up to
    a sixth of the form along some directions (the predictions call it outside the
    optimizer's float64 scope)."""
    lab_c = jnp.asarray(lab_c, dtype=jnp.float64)
    h = _METRIC_STEP
    eye = np.eye(3)
    pairs = [(i, j) for i in range(3) for j in range(i + 1, 3)]
    # The six directions (axes, then pairs of axes), each with both signs, in one call:
    # CIEDE2000 runs op by op here, and one call over all twelve steps costs what one step did.
    steps = h * np.array([*eye, *(eye[i] + eye[j] for i, j in pairs)])
    steps = np.concatenate([steps, -steps])
    lab = jnp.asarray(lab_c)[None] + jnp.asarray(steps).reshape((12,) + (1,) * (lab_c.ndim - 1) + (3,))
    q = np.asarray(colorimetry.delta_e_2000(lab, jnp.broadcast_to(lab_c, lab.shape)), dtype=np.float64) ** 2
    even = 0.5 * (q[:6] + q[6:])  # the even part: the quadratic form's value along each direction

    G = np.empty(lab_c.shape + (3,))
    for i in range(3):
        G[..., i, i] = even[i] / h ** 2
    for k, (i, j) in enumerate(pairs):
        G[..., i, j] = G[..., j, i] = (even[3 + k] - even[i] - even[j]) / (2 * h * h)
    return G


@float64
def _xyz_metric(c: np.ndarray, lab_c: np.ndarray) -> np.ndarray:
    """Jl' G Jl: CIEDE2000's local quadratic form in XYZ at the target c (Jl = d Lab / d XYZ)."""
    Jl = np.asarray(jax.jacfwd(colorimetry.xyz_to_lab)(jnp.asarray(c, dtype=jnp.float64)))
    return Jl.T @ de2000_metric(lab_c) @ Jl


def check_objective(objective: str, spp: int) -> None:
    """Raise ValueError unless ``objective`` is one of :data:`OBJECTIVES` and ``spp`` a whole
    number in 1..:data:`MAX_OBJECTIVE_SPP` (checked before any long work)."""
    if objective not in OBJECTIVES:
        raise ValueError(f"unknown objective {objective!r}; one of: {', '.join(OBJECTIVES)}")
    if isinstance(spp, bool) or not (isinstance(spp, (int, np.integer)) and 1 <= spp <= MAX_OBJECTIVE_SPP):
        raise ValueError(f"the objective's spp must be a whole number in 1..{MAX_OBJECTIVE_SPP}, not {spp!r}")


def objective_label(objective: str, spp: int) -> str:
    """How a record names the objective: ``J`` or ``stratified, spp 64``."""
    return objective if objective == "J" else f"{objective}, spp {spp}"


def with_objective(problem: Problem, objective: str = "J", spp: int = DEFAULT_OBJECTIVE_SPP,
                   pixels: np.ndarray | None = None) -> Problem:
    """The same problem standing for ``objective`` (design §4.6).

    ``"J"``: §4.1, the problem as built. ``"stratified"``: the linearised root-mean-square
    CIEDE2000 of a pixel that averages ``spp`` samples of C(u), one u in each of ``spp``
    equal strata, times sqrt(spp) (one path's units, like J). Its arrays gain the strata's
    edges (breakpoints of the u-quadrature) and CIEDE2000's quadratic form in XYZ at each
    target colour; ``spp=1`` is a pixel of independent samples at any spp. ``"pixels"``: the
    predicted mean over a scene's pixels of the same at ``spp``, the surface colours being a
    hat basis of the pixels' spectra and ``pixels`` (or the problem's own) the weights of
    :func:`wavelength_pdf.predict.pixel_weights`, made for that spp.
    """
    check_objective(objective, spp)
    drop = ("strata", "strata_metric", "pixel_ws", "pixel_wi", "pixel_w1", "pixel_wk")
    arrays = {k: v for k, v in problem.arrays.items() if k not in drop}
    if objective == "J":
        return replace(problem, arrays=arrays, objective="J", spp=1)
    spp = int(spp)
    if objective == "pixels":
        pixels = problem.pixels if pixels is None else np.asarray(pixels, dtype=np.float64)
        k = problem.refl.shape[0] if problem.batched else 0
        levels = spp.bit_length() - 2  # with the net's cells: one weight per 2^k strata, k = 1 … m - 1
        if (pixels is None or not problem.batched or pixels.shape[1:] != (3 * k, 3 * k)
                or pixels.shape[0] not in (3, 3 + max(levels, 0))):
            raise ValueError("the pixels objective needs a hat basis as surface colours and its weights "
                             f"(3, {3 * k}, {3 * k}), or (3 + {max(levels, 0)}, ...) with the net's cells "
                             "(wavelength_pdf.predict.pixel_weights)")
        extra = {"strata": np.arange(1, spp, dtype=np.float64) / spp, "pixel_ws": pixels[0],
                 "pixel_wi": pixels[1], "pixel_w1": pixels[2]}
        if pixels.shape[0] > 3 and levels > 0:
            extra["pixel_wk"] = pixels[3:]
        arrays.update(jax.device_put(extra))
        return replace(problem, arrays=arrays, objective=objective, spp=spp, pixels=pixels)
    c = np.atleast_2d(problem.c)
    lab = np.atleast_2d(problem.lab_c)
    metric = np.stack([_xyz_metric(ck, lk) for ck, lk in zip(c, lab)])
    extra = {"strata": np.arange(1, spp, dtype=np.float64) / spp,
             "strata_metric": metric if problem.batched else metric[0]}
    arrays.update(jax.device_put(extra))
    return replace(problem, arrays=arrays, objective=objective, spp=spp)


# One compiled function, not a dozen one-operation ones (eager jnp on a NumPy array).
_xyz_to_lab_jit = aot.DiskJit(jax.jit(colorimetry.xyz_to_lab), "xyz_to_lab")
