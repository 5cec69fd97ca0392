"""The objective J of design §4, evaluated exactly for one lamp spectrum.

For a table of four densities p_k on the grid lambda_0..lambda_M (design §1) and a path that
carries the lamp's spectrum I, the estimator of the lamp's colour is

    C(u) = sum_j f(lambda_j(u)) / sum_k p_k(lambda_j(u)),   f = I * (xbar, ybar, zbar),

with lambda_j(u) = F_j^-1(u) (one u for all four wavelengths). Its mean is the target
c = integral of f over [lambda_0, lambda_M]. Both are scaled so that c has Y = 1, and

    J = integral over u in [0, 1] of CIEDE2000(Lab(C(u)), Lab(c)) du.

How J is integrated
-------------------
The spectrum is used at its own resolution and the CMFs at theirs (1 nm), both linear
between their nodes, so f is piecewise quadratic on the union of spectrum, CMF and table
nodes. C(u) is smooth except where some lambda_j(u) crosses one of those nodes, i.e. at
u = F_j(node). Those values are the breakpoints in u: between two consecutive breakpoints
the integrand is smooth and Gauss-Legendre converges fast, so J computed with ``ORDER``
and ``ORDER_FINE`` points per piece agree closely (both are reported). The breakpoints
move with the densities, and J is differentiated through them (Leibniz's rule comes out
of automatic differentiation of the quadrature).

What no breakpoint can know is where CIEDE2000 itself is not smooth: it jumps where the
hue of C(u) crosses the opposite of the target's hue (the hue-mean branch; Sharma et al.
2005) and has a cone point where C(u) passes through c. On optimized tables J and J_fine
agree to ~1e-6 relative; on tables whose estimates wander round the hue circle or sweep
straight through c (a single emission line) the difference is 1e-5 to 1e-3.

The second moment of C(u), which the health check and the solvers' variance penalty
use, is split into sum_j E[(f / M)(lambda_j)^2] = integral of f^2 / M (M = sum_k p_k),
integrated in closed form in wavelength space where fireflies (small M) live, plus the
cross terms, which the u-quadrature handles well.

All arrays that describe a problem are padded to a multiple of ``_PAD`` entries, so the
jitted functions compile once per size class rather than once per spectrum.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from . import aot, colorimetry, sampling

Array = jax.Array

from .model import DEFAULT_GRID, check_objective_nodes, check_table_nodes, product_integrals  # noqa: E402

#: Gauss-Legendre points per piece between u-breakpoints: the resolution the solvers
#: search with and report (J), and the refined one that shows J has converged (J_fine;
#: on the reference tables the two agree to ~1e-4 relative, and order 6 adds nothing
#: visible to order 4).
ORDER = 2
ORDER_FINE = 4

#: Gauss-Legendre points per piece while the solvers search (the midpoint rule: the
#: pieces between breakpoints are short, and the tables found are judged at ``ORDER``
#: and ``ORDER_FINE``).
SEARCH_ORDER = 1

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
        return _from_nodes(problem.name, problem.source, problem.grid, x[keep], Y[keep, 0], Y[keep, 1:4])
    return _from_nodes(problem.name, problem.source, problem.grid, x[keep], Y[keep, 0], Y[keep, 1:4],
                       refl=Y[keep, 4:].T, weights=problem.weights,
                       reflectance_set=problem.reflectance_set)


# --- Pure functions of (densities, problem arrays) -----------------------------------


def f_at(arr: dict, lam: Array) -> Array:
    """f(lam) = I(lam) * cmf(lam), shape lam.shape + (3,); zero outside the grid range.

    With surface colours (design §4.5) f = I R_k cmf for every colour k, shape
    (K,) + lam.shape + (3,)."""
    x = arr["nodes"]
    n = x.shape[0]
    i = jnp.clip(jnp.searchsorted(x, lam, side="right") - 1, 0, n - 2)
    w = (lam - x[i]) / (x[i + 1] - x[i])
    w = jnp.clip(w, 0.0, 1.0)
    spec = arr["spec"][..., i] * (1.0 - w) + arr["spec"][..., i + 1] * w
    cmf = arr["cmf"][i] * (1.0 - w)[..., None] + arr["cmf"][i + 1] * w[..., None]
    inside = (lam >= x[0]) & (lam <= arr["bp"][-1])
    return jnp.where(inside[..., None], spec[..., None] * cmf, 0.0)


def _normalized(grid: Array, P: Array) -> tuple[Array, Array]:
    return jax.vmap(lambda p: sampling.normalized_with_cdf(grid, p))(P)


def _cdf_at_breakpoints(arr: dict, PN: Array, FF: Array) -> Array:
    """F_j(x) for every breakpoint wavelength x and density j, shape (4, Nb)."""
    grid = arr["grid"]
    seg, t = arr["bp_seg"], arr["bp_t"]
    w = t / (grid[seg + 1] - grid[seg])

    def one(pn, F):
        p_x = pn[seg] * (1.0 - w) + pn[seg + 1] * w
        return jnp.clip(F[seg] + 0.5 * t * (pn[seg] + p_x), 0.0, 1.0)

    return jax.vmap(one)(PN, FF)


def _pieces(breaks: Array, glx: Array, glw: Array) -> tuple[Array, Array]:
    """Gauss-Legendre points and weights on every interval between sorted breakpoints."""
    b = jnp.sort(jnp.concatenate([jnp.zeros(1), breaks.ravel(), jnp.ones(1)]))
    a, width = b[:-1], b[1:] - b[:-1]
    u = (a[:, None] + width[:, None] * glx[None, :]).ravel()
    wt = (width[:, None] * glw[None, :]).ravel()
    return u, wt


def _table_estimate(arr: dict, PN: Array, FF: Array, u: Array) -> Array:
    """C(u) for normalized densities PN with CDFs FF, shape u.shape + (3,)."""
    grid = arr["grid"]
    seg, t = jax.vmap(lambda pn, F: sampling.sample_segment(grid, pn, F, u))(PN, FF)
    lam = grid[seg] + t  # (4, n)
    w = t / (grid[seg + 1] - grid[seg])
    # sum_k p_k(lambda_j): every density is linear on the segment lambda_j fell into.
    msum = jnp.sum(PN[:, seg] * (1.0 - w)[None] + PN[:, seg + 1] * w[None], axis=0)
    f = f_at(arr, lam)  # ([K,] 4, n, 3)
    pos = msum > 0
    ratio = jnp.where(pos[..., None], f / jnp.where(pos, msum, 1.0)[..., None], 0.0)
    return jnp.sum(ratio, axis=-3)


def _table_quadrature(P: Array, arr: dict, glx: Array, glw: Array):
    """Points u, weights and C(u) of the piecewise Gauss-Legendre rule for table P.

    The breakpoints F_j(node) of all four densities are sorted together; a running
    maximum over the sorted list tells, for every piece, the node interval each
    lambda_j(u) lies in (and hence its table segment), so no search is needed per point.
    """
    grid = arr["grid"]
    x = arr["nodes"]
    nd = sampling.N_DENSITIES
    PN, FF = _normalized(grid, P)
    Fb = _cdf_at_breakpoints(arr, PN, FF)  # (4, Nb)
    nb = Fb.shape[1]
    flat = Fb.ravel()
    order = jnp.argsort(flat, stable=True)
    b = flat[order]
    lab_j = order // nb
    lab_n = arr["bp_idx"][order % nb]
    own = lab_j[None, :] == jnp.arange(nd)[:, None]
    cur = jax.lax.cummax(jnp.where(own, lab_n[None, :], -1), axis=1)[:, :-1]
    cur = jnp.maximum(cur, 0)  # (4, K-1): node interval of lambda_j on every piece
    width = b[1:] - b[:-1]
    u = b[:-1, None] + width[:, None] * glx[None, :]  # (K-1, g)
    wt = (width[:, None] * glw[None, :]).ravel()
    u = u.ravel()
    g = glx.shape[0]
    node = jnp.repeat(cur, g, axis=1)  # (4, n)
    seg = arr["node_tseg"][node]
    t = jax.vmap(lambda pn, F, i: sampling.solve_in_segment(grid, pn, F, i, u))(PN, FF, seg)
    lam = grid[seg] + t
    # f on the node interval, the mixture on the table segment.
    wn = jnp.clip((lam - x[node]) / (x[node + 1] - x[node]), 0.0, 1.0)
    if arr["spec"].ndim == 1:
        # One white surface: exactly the operations (and order) the solvers were tuned on;
        # a reordering changes rounding, and on hard lamps that moves the optimum found.
        spec = arr["spec"][node] * (1.0 - wn) + arr["spec"][node + 1] * wn
        cmf = arr["cmf"][node] * (1.0 - wn)[..., None] + arr["cmf"][node + 1] * wn[..., None]
        f = spec[..., None] * cmf  # (4, n, 3)
        w = t / (grid[seg + 1] - grid[seg])
        msum = jnp.sum(PN[:, seg] * (1.0 - w)[None] + PN[:, seg + 1] * w[None], axis=0)
        pos = msum > 0
        ratio = jnp.where(pos[..., None], f / jnp.where(pos, msum, 1.0)[..., None], 0.0)
        return u, wt, jnp.sum(ratio, axis=0), jnp.sum(ratio * ratio, axis=0)
    cmf = arr["cmf"][node] * (1.0 - wn)[..., None] + arr["cmf"][node + 1] * wn[..., None]
    w = t / (grid[seg + 1] - grid[seg])
    msum = jnp.sum(PN[:, seg] * (1.0 - w)[None] + PN[:, seg + 1] * w[None], axis=0)
    pos = msum > 0
    safe = jnp.where(pos, msum, 1.0)

    # Surface colours (design §4.5): everything above is shared; only f differs per colour.
    def terms(spec_nodes):
        spec = spec_nodes[node] * (1.0 - wn) + spec_nodes[node + 1] * wn
        f = spec[..., None] * cmf  # (4, n, 3)
        ratio = jnp.where(pos[..., None], f / safe[..., None], 0.0)
        return jnp.sum(ratio, axis=0), jnp.sum(ratio * ratio, axis=0)

    C, D = jax.vmap(terms)(arr["spec"])
    return u, wt, C, D


def _delta_e(arr: dict, C: Array) -> Array:
    """CIEDE2000 of C(u) ((n, 3), or (K, n, 3) with surface colours) against the target."""
    lab_c = arr["lab_c"][:, None, :] if C.ndim == 3 else arr["lab_c"]
    return colorimetry.delta_e_2000(colorimetry.xyz_to_lab(C), lab_c)


def _mean_over_colours(arr: dict, per_colour: Array) -> Array:
    """J from the per-colour J's: itself, or their weighted mean (design §4.5)."""
    return jnp.sum(arr["weights"] * per_colour) if "weights" in arr else per_colour


def _table_J(P: Array, arr: dict, glx: Array, glw: Array) -> Array:
    u, wt, C, _ = _table_quadrature(P, arr, glx, glw)
    return _mean_over_colours(arr, jnp.sum(wt * _delta_e(arr, C), axis=-1))


# --- The second moment: diagonal part exactly in wavelength space -----------------------


def _powers(x: Array, n: int) -> Array:
    """x^0 .. x^(n-1) by repeated products, stacked on a new last axis. Cheaper than
    pow (exp and log per element; this function ran three times slower with it) and with
    exact derivatives at x = 0 (a power with exponent 0 at base 0 has a NaN derivative)."""
    out = [jnp.ones_like(x)]
    for _ in range(n - 1):
        out.append(out[-1] * x)
    return jnp.stack(out, axis=-1)


_K5 = np.arange(5)
_BINOM5 = np.array([[1, 0, 0, 0, 0], [1, 1, 0, 0, 0], [1, 2, 1, 0, 0], [1, 3, 3, 1, 0], [1, 4, 6, 4, 1]],
                   dtype=np.float64) * (_K5[None, :] <= _K5[:, None])  # C(k, i), i <= k
_EXPO5 = np.clip(_K5[:, None] - _K5[None, :], 0, None)  # k - i
_INV_I5 = np.where(_K5 > 0, 1.0 / np.maximum(_K5, 1), 0.0)  # 1 / i, 0 for i = 0
_SERIES_TERMS = 24
_SERIES = 1.0 / (_K5[None, :] + np.arange(_SERIES_TERMS)[:, None] + 1.0)  # 1 / (k + n + 1)


def _quartic_over_linear(e: Array, a: Array, b: Array, h: Array) -> Array:
    """Integral over t in [0, h] of (e0 + e1 t + ... + e4 t^4) / (a + b t), a, b >= 0.

    Closed form (log plus polynomial) when b h / a is not small, a power series in
    b t / a when it is (where the closed form cancels), and h^k / (k b) for a = 0 (infinite
    if the numerator does not vanish at t = 0). Elementwise over leading axes; e has a
    trailing axis of 5. Integer powers are products (``_powers``).
    """
    a_pos = a > 0
    a_s = jnp.where(a_pos, a, 1.0)
    b_pos = b > 0
    b_s = jnp.where(b_pos, b, 1.0)
    r = b * h / a_s
    small = a_pos & (r <= 0.2)
    hp = _powers(h, 6)  # h^0 .. h^5
    # Series: I_k = h^(k+1) / a * sum_n (-r)^n / (k + n + 1).
    r_s = jnp.where(small, r, 0.0)
    I_series = hp[..., 1:] / a_s[..., None] * (_powers(-r_s, _SERIES_TERMS) @ _SERIES)
    # Closed form: z = a + b t, I_k = b^-(k+1) [(-a)^k log(z1/z0) + sum_i C(k,i) (-a)^(k-i) (z1^i - z0^i) / i].
    z0 = a_s
    z1 = a_s + b * h
    big = a_pos & ~small
    log_ratio = jnp.log(jnp.where(big, z1 / z0, 2.0))
    pa = _powers(-a_s, 5)  # (-a)^0 .. (-a)^4
    diff_pow = (_powers(z1, 5) - _powers(z0, 5)) * _INV_I5  # (z1^i - z0^i) / i
    poly = jnp.sum(_BINOM5 * pa[..., _EXPO5] * diff_pow[..., None, :], axis=-1)
    inv_b = 1.0 / b_s
    I_closed = (pa * log_ratio[..., None] + poly) * _powers(inv_b, 6)[..., 1:]
    # a = 0: the k = 0 term diverges unless e0 = 0.
    I_zero = hp[..., :5] * _INV_I5 * inv_b[..., None]
    val_zero = jnp.where(e[..., 0] == 0, jnp.sum(e * I_zero, axis=-1), jnp.inf)
    val_zero = jnp.where(b_pos, val_zero, jnp.where(jnp.all(e == 0, axis=-1), 0.0, jnp.inf))
    I = jnp.where(small[..., None], I_series, I_closed)
    return jnp.where(a_pos, jnp.sum(e * I, axis=-1), val_zero)


def _diag_second_moment(arr: dict, msum_nodes: Array) -> Array:
    """Integral of f^2 / M, per channel ((K, 3) with surface colours); see ``_diag_one``."""
    if arr["spec"].ndim == 2:
        return jax.vmap(lambda s: _diag_one({**arr, "spec": s}, msum_nodes))(arr["spec"])
    return _diag_one(arr, msum_nodes)


def _diag_one(arr: dict, msum_nodes: Array) -> Array:
    """Integral of f^2 / M over the grid range, per channel, exactly.

    M = sum_k p_k is the mixture (times 4) given at the table nodes. This is the part
    sum_j E[(f(lambda_j) / M(lambda_j))^2] of E[C^2], where fireflies live: done in
    wavelength space (u = F_j(lambda)), where on every node interval f^2 is a quartic and
    M is linear, so it has no quadrature error however small M gets.
    """
    grid = arr["grid"]
    x = arr["nodes"]
    h = x[1:] - x[:-1]
    s0, s1 = arr["spec"][:-1], (arr["spec"][1:] - arr["spec"][:-1]) / h
    k0 = arr["cmf"][:-1]
    k1 = (arr["cmf"][1:] - arr["cmf"][:-1]) / h[:, None]
    A = s0[:, None] * k0
    B = s0[:, None] * k1 + s1[:, None] * k0
    Cq = s1[:, None] * k1
    d = jnp.stack([A * A, 2 * A * B, B * B + 2 * A * Cq, 2 * B * Cq, Cq * Cq], axis=-1)  # (n, 3, 5)
    m = jnp.interp(x, grid, msum_nodes, left=0.0, right=0.0)
    m0, m1 = m[:-1], m[1:]
    # Orient every interval so that M is smallest at t = 0: t -> h - t flips the quartic.
    flip = m1 < m0
    binom = jnp.array([[1, 0, 0, 0, 0], [1, 1, 0, 0, 0], [1, 2, 1, 0, 0], [1, 3, 3, 1, 0], [1, 4, 6, 4, 1]], dtype=h.dtype)
    kk = jnp.arange(5.0)
    # e_i = (-1)^i sum_{k >= i} C(k, i) d_k h^(k - i)
    hp = h[:, None, None] ** jnp.clip(kk[:, None] - kk[None, :], 0.0, None)  # (n, k, i)
    flipped = jnp.einsum("nck,ki,nki->nci", d, binom, hp) * (-1.0) ** kk
    e = jnp.where(flip[:, None, None], flipped, d)
    a = jnp.minimum(m0, m1)
    b = jnp.abs(m1 - m0) / h
    a3 = jnp.broadcast_to(a[:, None], e.shape[:2])
    b3 = jnp.broadcast_to(b[:, None], e.shape[:2])
    h3 = jnp.broadcast_to(h[:, None], e.shape[:2])
    vals = _quartic_over_linear(e, a3, b3, h3)
    # Intervals past the last real node (padding) are not part of the range.
    inside = (x[1:] <= grid[-1])[:, None]
    return jnp.sum(jnp.where(inside, vals, 0.0), axis=0)


def _moments(arr: dict, wt: Array, C: Array, D: Array, diag_exact: Array):
    """J, E[C] and E[(C - c)^2] (per channel).

    E[C^2] = (exact diagonal part, wavelength space) + (cross terms, u-quadrature): the
    quadrature only sees C^2 - sum_j (f_j / M_j)^2, which has no firefly peaks.
    """
    if C.ndim == 2:  # one white surface, as before surface colours existed (see above)
        J = jnp.sum(wt * _delta_e(arr, C))
        m1 = jnp.sum(wt[:, None] * C, axis=0)
        cross = jnp.sum(wt[:, None] * (C * C - D), axis=0)
    else:
        J = _mean_over_colours(arr, jnp.sum(wt * _delta_e(arr, C), axis=-1))
        m1 = jnp.sum(wt[:, None] * C, axis=-2)
        cross = jnp.sum(wt[:, None] * (C * C - D), axis=-2)
    c = arr["c"]
    m2 = diag_exact + cross - 2.0 * c * m1 + c * c
    return J, m1, m2


def _table_moments(P: Array, arr: dict, glx: Array, glw: Array):
    u, wt, C, D = _table_quadrature(P, arr, glx, glw)
    PN = jax.vmap(lambda p: sampling.normalize(arr["grid"], p))(P)
    return _moments(arr, wt, C, D, _diag_second_moment(arr, jnp.sum(PN, axis=0)))


def _uniform_breaks(arr: dict, lo: Array, hi: Array) -> Array:
    x = (arr["bp"] - lo) / (hi - lo)
    j = jnp.arange(sampling.N_DENSITIES)[:, None] / sampling.N_DENSITIES
    return jnp.mod(x[None, :] - j, 1.0)


def _uniform_terms(arr: dict, u: Array) -> Array:
    """Stratified uniform terms f(lambda_j) / sum_k p_k(lambda_j), shape (4, n, 3): the
    balance heuristic over four uniform densities at the stratified wavelengths."""
    grid = arr["grid"]
    lo, hi = grid[0], grid[-1]
    lam = sampling.sample_stratified_uniform(lo, hi, u)  # (4, n)
    msum = sampling.N_DENSITIES * sampling.mixture_pdf(grid, sampling.stratified_uniform_table(grid), lam)
    return f_at(arr, lam) / msum[..., None]


def _uniform_estimate(arr: dict, u: Array) -> Array:
    """Stratified uniform C(u) = (hi - lo) / 4 * sum_j f(lambda_j)."""
    return jnp.sum(_uniform_terms(arr, u), axis=-3)


def _uniform_moments(arr: dict, glx: Array, glw: Array):
    grid = arr["grid"]
    u, wt = _pieces(_uniform_breaks(arr, grid[0], grid[-1]), glx, glw)
    terms = _uniform_terms(arr, u)
    msum = jnp.sum(sampling.stratified_uniform_table(grid), axis=0)
    return _moments(arr, wt, jnp.sum(terms, axis=-3), jnp.sum(terms * terms, axis=-3),
                    _diag_second_moment(arr, msum))


def penalized(P: Array, arr: dict, glx: Array, glw: Array, var_ref: Array, mu: Array, margin: Array):
    """J + mu * sum_c max(0, var_c / var_ref_c - (1 - margin))^2, and (J, E[C], E[(C-c)^2]).

    The objective of the solvers (see ``solvers``); with mu = 0 it is J itself. Every
    evaluation at ``ORDER`` goes through this one function, so it is compiled once (per
    size class) for searching, reporting and the health figures alike.
    """
    J, m1, m2 = _table_moments(P, arr, glx, glw)
    var = m2 - (m1 - arr["c"]) ** 2
    excess = jnp.maximum(var / var_ref - (1.0 - margin), 0.0)
    return J + mu * jnp.sum(excess * excess), (J, m1, m2)


# Jitted at the edge (where solvers and reports call in); shapes are fixed per size class.
# Their executables are also kept on disk (``aot``) when the compilation cache is on.
penalized_value_and_grad = aot.DiskJit(jax.jit(jax.value_and_grad(penalized, has_aux=True)),
                                       "penalized_value_and_grad")
_table_moments_jit = aot.DiskJit(jax.jit(_table_moments), "table_moments")
_uniform_moments_jit = aot.DiskJit(jax.jit(_uniform_moments), "uniform_moments")
# One compiled function, not a dozen one-operation ones (eager jnp on a NumPy array).
_xyz_to_lab_jit = aot.DiskJit(jax.jit(colorimetry.xyz_to_lab), "xyz_to_lab")


def _moments_at(problem: Problem, P: Array, order: int):
    glx, glw = gauss_legendre(order)
    if order == SEARCH_ORDER:
        one = np.ones(3)
        (_, aux), _ = penalized_value_and_grad(P, problem.arrays, glx, glw, one, 0.0, 0.0)
        return aux
    if order < ORDER_FINE:
        # The same compiled function as ORDER_FINE (one compilation fewer per process):
        # the rule's points repeated with zero weight.
        reps = -(-ORDER_FINE // order)
        glx = jax.device_put(np.tile(np.asarray(glx), reps)[:ORDER_FINE])
        glw = jax.device_put(np.concatenate([np.asarray(glw), np.zeros(ORDER_FINE - order)]))
    return _table_moments_jit(P, problem.arrays, glx, glw)


def gauss_legendre(order: int) -> tuple[Array, Array]:
    """Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(order)
    return jax.device_put(0.5 * (x + 1.0)), jax.device_put(0.5 * w)


# --- Public interface ----------------------------------------------------------------

_cache_dir: str | None = None


def enable_compilation_cache() -> str | None:
    """Keep compiled objectives on disk between runs (JAX's persistent compilation cache).

    Compiling the objective and its gradient takes 5-10 s per problem size; with the
    cache a later run (another spectrum, another process) loads them in about a second
    (``wavelength_pdf.compile_cache``: its place, size, ``warm`` and ``clear``).
    The objective's functions are also kept as whole executables (``aot``), which skips
    tracing and lowering them in a later process.
    The directory is ``$WAVELENGTH_PDF_JAX_CACHE`` if set (empty or ``off`` disables the
    cache), else ``$XDG_CACHE_HOME/wavelength-pdf/jax`` (``~/.cache/...``). The cache only
    holds compiled code: results do not depend on it. Returns the directory, or None.

    Compiled code from the folder runs in this process, so a folder that another user owns
    or that group or others may write to is not used (one warning, no cache; design §7); the
    executables kept by ``aot`` also carry a digest under the user's own key.
    """
    global _cache_dir
    if _cache_dir is not None:
        return _cache_dir or None
    from wavelength_pdf import compile_cache

    path = compile_cache.cache_dir()  # design §7: the folder, or None when turned off
    if path is None:
        _cache_dir = ""
        return None
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        unsafe = aot.check_cache_folder(path)
        if unsafe:
            warnings.warn(f"not using the compile cache {path}: {unsafe}; compiled code there "
                          "could have been written by someone else (make it yours with "
                          "chmod 700, or set WAVELENGTH_PDF_JAX_CACHE to another folder)",
                          RuntimeWarning, stacklevel=2)
            _cache_dir = ""
            aot.enable(None)
            return None
        jax.config.update("jax_compilation_cache_dir", str(path))
        aot.enable(path / "executables")
        # Every compiled function, however quick to compile: a process compiles ~30.
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    except (OSError, AttributeError, ValueError):
        _cache_dir = ""
        return None
    _cache_dir = str(path)
    return _cache_dir



def _check_table(problem: Problem, P) -> Array:
    P = jnp.asarray(P, dtype=jnp.float64)
    if P.shape != (sampling.N_DENSITIES, problem.grid.size):
        raise ValueError(
            f"densities must have shape ({sampling.N_DENSITIES}, {problem.grid.size}), got {P.shape}"
        )
    return P


def target(problem: Problem) -> np.ndarray:
    """The exact target XYZ c (Y = 1)."""
    return problem.c.copy()


def estimate(problem: Problem, P, u) -> np.ndarray:
    """The estimator C(u) of the table P (4, M+1) at the u values given, shape (n, 3)."""
    P = _check_table(problem, P)
    arr = problem.arrays
    PN, FF = _normalized(arr["grid"], P)
    return np.asarray(_table_estimate(arr, PN, FF, jnp.atleast_1d(jnp.asarray(u))))


def uniform_estimate(problem: Problem, u) -> np.ndarray:
    """The stratified-uniform estimator C(u), shape (n, 3)."""
    return np.asarray(_uniform_estimate(problem.arrays, jnp.atleast_1d(jnp.asarray(u))))


def J(problem: Problem, P, order: int = ORDER) -> float:
    """J of the table P (any positive scale per density) with ``order`` GL points a piece."""
    return float(_moments_at(problem, _check_table(problem, P), order)[0])


def J_pair(problem: Problem, P) -> tuple[float, float]:
    """J at the optimizer's resolution and at the refined one: (J, J_fine)."""
    return J(problem, P, ORDER), J(problem, P, ORDER_FINE)


def value_and_grad(problem: Problem):
    """A function P -> (J, dJ/dP) at ``ORDER`` (jitted, float64)."""
    glx, glw = gauss_legendre(ORDER)
    arr = problem.arrays
    one = jnp.ones(3)

    def vg(P):
        (val, _), g = penalized_value_and_grad(jnp.asarray(P, dtype=jnp.float64), arr, glx, glw, one, 0.0, 0.0)
        return val, g

    return vg


def objective_fn(problem: Problem, order: int = ORDER):
    """The pure function P -> J (not jitted), for composing with parameterizations."""
    glx, glw = gauss_legendre(order)
    arr = problem.arrays
    return partial(_table_J, arr=arr, glx=glx, glw=glw)


def moments_fn(problem: Problem, order: int = ORDER):
    """The pure function P -> (J, E[C], E[(C - c)^2]) (not jitted)."""
    glx, glw = gauss_legendre(order)
    arr = problem.arrays
    return partial(_table_moments, arr=arr, glx=glx, glw=glw)


def moments(problem: Problem, P, order: int = ORDER_FINE) -> tuple[float, np.ndarray, np.ndarray]:
    """J, E[C] and E[(C - c)^2] over u (per channel) of the table P."""
    J_, m1, m2 = _moments_at(problem, _check_table(problem, P), order)
    return float(J_), np.asarray(m1), np.asarray(m2)


def uniform_moments(problem: Problem, order: int = ORDER) -> tuple[float, np.ndarray, np.ndarray]:
    """J, E[C] and E[(C - c)^2] of stratified uniform sampling over the grid range."""
    glx, glw = gauss_legendre(order)
    J_, m1, m2 = _uniform_moments_jit(problem.arrays, glx, glw)
    return float(J_), np.asarray(m1), np.asarray(m2)


def uniform_J(problem: Problem, order: int = ORDER) -> float:
    """J of stratified uniform sampling, lambda_j = lo + (hi - lo) ((u + j/4) mod 1)."""
    return uniform_moments(problem, order)[0]
