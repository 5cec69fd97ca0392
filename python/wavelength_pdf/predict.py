"""Predicted image error of a wavelength table under a lamp.

The optimizer ranks tables by J (design §4.1), the mean CIEDE2000 of *one* path's colour
estimate C(u). An image pixel averages N paths, and a low-discrepancy pixel sampler draws the
N values of u stratified (one per stratum [i/N, (i+1)/N) for a power-of-two N). These
functions predict the squared CIEDE2000 of a pixel that sees the lamp on a white surface (or
on given surface colours), so that a benchmark can check whether the ranking of tables by a
prediction is the ranking of the images it measures (``evaluation.benchmark.predict``).

Each prediction is a function ``(table, spectrum, spp, pixel_sampler, reflectances) ->``
predicted mean squared CIEDE2000 of the pixel's colour (units: the white surface at Y = 1,
Lab relative to D65 at Y = 1, as J). Only ratios between tables under the same lamp are
meant to be compared; every prediction is invariant to the lamp's power (the objective's
problem scales the target to Y = 1).

- ``J``: today's objective (design §4.1, :func:`wavelength_pdf.objective.J`), squared so that
  it is in the units of a squared error. It does not know N or the pixel sampler.
- ``stratified``: E[CIEDE2000(mean of N samples of C(u), c)^2], u stratified over N strata
  (``sobol``) or independent (``independent``), by Monte Carlo over sample sets drawn from
  C(u) tabulated on a fine grid of u. ``stratified-de``: E[CIEDE2000]^2, the same in
  squared units, less driven by rare huge errors.
- ``covariance``: the covariance of the mean of N samples (per-stratum covariances / N^2,
  or the whole covariance / N), mapped to Lab by the Jacobian at the target colour and
  measured by CIEDE2000's local quadratic form there (``covariance-lab``: by plain Lab
  distance). Linearised, so it is the small-noise limit of ``stratified``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Callable, Sequence

import numpy as np

from wavelength_pdf.precision import float64

#: Points of the fine u grid on which C(u) is tabulated (midpoints of 2^15 cells): every
#: power-of-two N up to 4096 divides it, so each stratum holds whole cells. At 2^15, a 1 nm
#: line under the uniform table (0.0025 of u per wavelength) spans ~80 cells.
U_POINTS = 2 ** 15
#: Sample sets of the Monte Carlo of ``stratified`` (its relative standard error is about
#: sqrt(2 / MC_SETS) for Gaussian-like errors: ~1.6 %).
MC_SETS = 8192
PIXEL_SAMPLERS = ("sobol", "independent")


@dataclass(frozen=True)
class PathColours:
    """C(u) of one table under one lamp on a fine grid of u (midpoints of equal cells).

    Attributes
    ----------
    C : (K, U, 3) array
        XYZ estimate of each colour (K = 1: the white surface) at each u.
    target : (K, 3) array
        The exact colours c_k (the white surface has Y = 1).
    weights : (K,) array
        Weight of each colour (summing to 1).
    J : float
        Today's objective for the table (design §4.1 / §4.5).
    """

    C: np.ndarray
    target: np.ndarray
    weights: np.ndarray
    J: float


#: Tables are given extra grid nodes up to a multiple of this many (see :func:`padded`).
GRID_CLASS = 512


def padded(table, nodes=(), size_class: int = GRID_CLASS):
    """The same densities on a grid of a multiple of ``size_class`` nodes.

    A piecewise-linear density is unchanged by a node inserted inside a segment with the
    interpolated value, so this changes no C(u) (J moves by its quadrature's error only:
    more breakpoints). It lets the objective's compiled functions (one per array shape,
    ~15 s each) serve every table and lamp of a size class instead of compiling once per
    table: the nodes inserted first are those the objective adds anyway (``nodes``, the
    lamp's own, and whole nanometres, the CMFs' grid), so that the objective's union of
    spectrum, CMF and table nodes is the padded grid itself, the same size for every lamp
    of the class; then midpoints of the widest segments."""
    from wavelength_pdf.table import Table

    grid = np.asarray(table.grid, dtype=np.float64)
    lo, hi = grid[0], grid[-1]
    extra = np.union1d(np.asarray(nodes, dtype=np.float64), np.arange(np.ceil(lo), np.floor(hi) + 1.0))
    new = np.union1d(grid, extra[(extra > lo) & (extra < hi)])
    want = -(-new.size // size_class) * size_class
    while new.size < want:
        gaps = np.diff(new)
        take = np.argsort(-gaps, kind="stable")[: want - new.size]
        new = np.union1d(new, new[take] + 0.5 * gaps[take])
    pdfs = np.stack([np.interp(new, grid, p) for p in np.asarray(table.pdfs, dtype=np.float64)])
    return Table(new, pdfs, list(table.comments))


@lru_cache(maxsize=1)
def _estimate_jit():
    import jax

    from wavelength_pdf import quadrature

    # objective.estimate runs op by op (seconds for 2^15 points); the same two steps jitted.
    def est(arr, P, u):
        PN, FF = quadrature.normalized(arr["grid"], P)
        return quadrature.table_estimate(arr, PN, FF, u)

    return jax.jit(est)


@float64
def path_colours(table, spectrum, reflectances=None, points: int = U_POINTS) -> PathColours:
    """Tabulate C(u) of ``table`` (a :class:`~wavelength_pdf.table.Table`) under ``spectrum``
    with the objective's own estimator (design §1.3) on ``points`` midpoints of u."""
    import jax.numpy as jnp

    from wavelength_pdf import objective
    from wavelength_pdf.compile_cache import enable_compilation_cache
    from wavelength_pdf.problem import make_problem

    enable_compilation_cache()
    table = padded(table, spectrum.wavelengths)
    problem = make_problem(spectrum, grid=table.grid, reflectances=reflectances)
    u = (np.arange(points) + 0.5) / points
    P = np.asarray(table.pdfs, dtype=np.float64)
    C = np.asarray(_estimate_jit()(problem.arrays, jnp.asarray(P), jnp.asarray(u)))
    target = np.asarray(objective.target(problem), dtype=np.float64)
    if C.ndim == 2:
        C, target = C[None], target[None]
    weights = (np.ones(1) if problem.weights is None else np.asarray(problem.weights, dtype=np.float64))
    return PathColours(C, target, weights, objective.J(problem, P))


@lru_cache(maxsize=1)
def _white_xy() -> np.ndarray:
    import colour

    from wavelength_pdf.colorimetry import white_d65

    return np.asarray(colour.XYZ_to_xy(white_d65()))


def lab(xyz: np.ndarray) -> np.ndarray:
    """CIELAB of XYZ (white surface Y = 1 scale) relative to D65 at Y = 1, as J's (colour-science)."""
    import colour

    return np.asarray(colour.XYZ_to_Lab(np.asarray(xyz, dtype=np.float64), _white_xy()))


def delta_e2000(lab1: np.ndarray, lab2: np.ndarray) -> np.ndarray:
    import colour

    return np.asarray(colour.delta_E(lab1, lab2, method="CIE 2000"), dtype=np.float64)


def _check(spp: int, pixel_sampler: str, points: int) -> None:
    if pixel_sampler not in PIXEL_SAMPLERS:
        raise ValueError(f"pixel sampler must be one of {PIXEL_SAMPLERS}, not {pixel_sampler!r}")
    if spp < 1 or (pixel_sampler == "sobol" and points % spp):
        raise ValueError(f"spp {spp} must divide the {points} points of the u grid")


def stratified_de2(pc: PathColours, spp: int, pixel_sampler: str = "sobol", sets: int = MC_SETS,
                   seed: int = 0, power: int = 2) -> float:
    """Candidate (b): E[CIEDE2000(mean of ``spp`` samples of C(u), c)^2], by Monte Carlo.

    ``sobol``: one u per stratum (a (0,1)-sequence's 1-D projection, which pbrt-v4's Sobol
    samplers give each dimension at power-of-two spp); ``independent``: u uniform. With
    ``power=1``, E[CIEDE2000] squared instead: the same up to the spread of the error when it
    is Gaussian-like, far less driven by rare huge errors (fireflies). A u is one
    of the fine grid's cells (C at its midpoint): the grid resolves C(u) far finer than a
    stratum, so this is the continuous draw up to the grid's resolution."""
    K, U, _ = pc.C.shape
    _check(spp, pixel_sampler, U)
    rng = np.random.default_rng(seed)
    if pixel_sampler == "sobol":
        cells = U // spp
        idx = np.arange(spp)[None, :] * cells + rng.integers(0, cells, size=(sets, spp))
    else:
        idx = rng.integers(0, U, size=(sets, spp))
    total = 0.0
    for k in range(K):
        mean = pc.C[k][idx].mean(axis=1)  # (sets, 3)
        de = delta_e2000(lab(mean), lab(pc.target[k])[None, :])
        total += pc.weights[k] * float(np.mean(de ** power))
    return total if power == 2 else total ** (2.0 / power)


def _lab_jacobian(xyz: np.ndarray) -> np.ndarray:
    """d Lab / d XYZ at ``xyz`` by central differences (Lab is smooth away from XYZ = 0)."""
    h = 1e-6 * max(float(np.max(np.abs(xyz))), 1e-12)
    cols = [(lab(xyz + h * e) - lab(xyz - h * e)) / (2 * h) for e in np.eye(3)]
    return np.stack(cols, axis=1)


def expected_quadratic(lab_c: np.ndarray, cov_lab: np.ndarray, metric: str = "de2000") -> float:
    """E[d(Lab_c + e, Lab_c)^2] for a zero-mean error e with covariance ``cov_lab``, d taken
    as its local quadratic form: for q(e) = e' G e, E[q] = sum_i s_i q(v_i) over the
    eigenpairs (s_i, v_i) of the covariance, so three evaluations of CIEDE2000 along its
    principal axes give tr(G cov) without forming G (symmetrised over +-v, as CIEDE2000's
    mean chroma makes it slightly odd)."""
    s, V = np.linalg.eigh(0.5 * (cov_lab + cov_lab.T))
    s = np.clip(s, 0.0, None)
    if metric == "lab":
        return float(np.sum(s))
    if metric != "de2000":
        raise ValueError(f"metric must be 'de2000' or 'lab', not {metric!r}")
    # A step small against any colour difference, large against rounding (Lab is ~100).
    eps = 1e-4
    total = 0.0
    for si, v in zip(s, V.T):
        if si == 0.0:
            continue
        q = 0.5 * sum(float(delta_e2000(lab_c + sgn * eps * v, lab_c)) ** 2 for sgn in (1.0, -1.0)) / eps ** 2
        total += si * q
    return total


def mean_covariance(C: np.ndarray, spp: int, pixel_sampler: str = "sobol") -> np.ndarray:
    """Covariance (3, 3) of the mean of ``spp`` samples of the tabulated C(u) (U, 3): the
    per-stratum covariances summed over spp^2 (stratified), or the whole covariance over spp."""
    U = C.shape[0]
    _check(spp, pixel_sampler, U)
    if pixel_sampler == "independent":
        d = C - C.mean(axis=0)
        return d.T @ d / U / spp
    S = C.reshape(spp, U // spp, 3)
    d = S - S.mean(axis=1, keepdims=True)
    per_stratum = np.einsum("smi,smj->sij", d, d) / S.shape[1]
    return per_stratum.sum(axis=0) / spp ** 2


def covariance_de2(pc: PathColours, spp: int, pixel_sampler: str = "sobol", metric: str = "de2000") -> float:
    """Candidate (c): the linearised squared error of the mean of ``spp`` samples: its XYZ
    covariance mapped to Lab by the Jacobian at the target colour, measured by CIEDE2000's
    local quadratic form (``metric='lab'``: Lab distance)."""
    total = 0.0
    for k in range(pc.C.shape[0]):
        cov = mean_covariance(pc.C[k], spp, pixel_sampler)
        Jl = _lab_jacobian(pc.target[k])
        total += pc.weights[k] * expected_quadratic(lab(pc.target[k]), Jl @ cov @ Jl.T, metric)
    return total


def hat_basis(centres, lo: float, hi: float):
    """The piecewise-linear functions of a spectrum known at ``centres`` (a spectral film's
    bucket centres inside [lo, hi]), as a reflectance set: function b is 1 at centre b, 0 at the
    others, linear between them and constant beyond the outer centres. Any spectrum
    T(λ) = sum_b t_b φ_b(λ) then has path colours sum_b t_b C_b(u), linear in t, so one
    tabulation of C_b serves every pixel of an image (:func:`pixel_de2`)."""
    from wavelength_pdf.reflectances import ReflectanceSet

    c = np.asarray(centres, dtype=np.float64)
    if c.ndim != 1 or c.size < 2 or not np.all(np.diff(c) > 0) or c[0] <= lo or c[-1] >= hi:
        raise ValueError(f"centres must increase strictly inside ({lo:g}, {hi:g}) nm, got {c}")
    wl = np.concatenate([[lo], c, [hi]])
    vals = np.zeros((c.size, wl.size))
    vals[:, 1:-1] = np.eye(c.size)
    vals[0, 0] = vals[-1, -1] = 1.0
    return ReflectanceSet("pixels", f"hat functions at {c.size} centres", wl, vals,
                          tuple(f"{x:g}nm" for x in c), np.full(c.size, 1.0 / c.size))


def basis_covariance(pc: PathColours, spp: int, pixel_sampler: str = "sobol") -> np.ndarray:
    """The cross-covariances M (B, 3, B, 3) of the basis' path colours over a pixel's mean of
    ``spp`` samples: per stratum summed over spp^2 (``sobol``), or the whole over spp
    (``independent``), as :func:`mean_covariance` for one colour."""
    B, U, _ = pc.C.shape
    _check(spp, pixel_sampler, U)
    if pixel_sampler == "independent":
        X = (pc.C - pc.C.mean(axis=1, keepdims=True)).transpose(1, 0, 2).reshape(U, B * 3)
        M = X.T @ X / U / spp
    else:
        S = pc.C.reshape(B, spp, U // spp, 3)
        X = (S - S.mean(axis=2, keepdims=True)).transpose(1, 2, 0, 3).reshape(U, B * 3)
        M = X.T @ X / (U // spp) / spp ** 2
    return M.reshape(B, 3, B, 3)


def basis_path_colours(table, spectrum, basis, points: int = U_POINTS) -> PathColours:
    """:func:`path_colours` for the hat basis of :func:`hat_basis`, where a function on which
    the lamp emits nothing (a line lamp's empty bands) has C_b(u) = 0 and colour 0 exactly,
    instead of being refused as a surface that reflects nothing of the lamp (the objective's
    rule for surface colours, design §4.5). The weights are the basis'; J is that of the
    functions the lamp lights."""
    lit, sub = lit_basis(spectrum, basis, float(table.grid[0]), float(table.grid[-1]))
    if lit.size == len(basis.labels):
        return path_colours(table, spectrum, basis, points)
    pc = path_colours(table, spectrum, sub, points)
    C = np.zeros((len(basis.labels),) + pc.C.shape[1:])
    target = np.zeros((len(basis.labels), 3))
    C[lit], target[lit] = pc.C, pc.target
    return PathColours(C, target, np.asarray(basis.weights, dtype=np.float64), pc.J)


def lit_basis(spectrum, basis, lo: float, hi: float):
    """The functions of the hat basis on which ``spectrum`` has luminance in [lo, hi]: their
    indices and the basis restricted to them (equal weights). The others' path colours are 0
    (a line lamp's empty bands). ValueError when none is lit."""
    from dataclasses import replace

    from wavelength_pdf.colorimetry import cmfs

    cwl, cval = cmfs()
    swl = np.asarray(spectrum.wavelengths, dtype=np.float64)
    lam = np.unique(np.concatenate([np.linspace(lo, hi, 4001), swl[(swl > lo) & (swl < hi)]]))
    E = np.interp(lam, swl, np.asarray(spectrum.values, dtype=np.float64), left=0.0, right=0.0)
    ybar = np.interp(lam, cwl, cval[:, 1], left=0.0, right=0.0)
    phi = np.stack([np.interp(lam, basis.wavelengths, v) for v in np.asarray(basis.values, dtype=np.float64)])
    lit = np.flatnonzero(np.trapezoid(phi * (E * ybar)[None, :], lam, axis=1) > 0)
    if lit.size == 0:
        raise ValueError(f"{spectrum.name}: no luminance in {lo:g}-{hi:g} nm")
    sub = replace(basis, values=np.asarray(basis.values)[lit], labels=tuple(basis.labels[i] for i in lit),
                  weights=np.full(lit.size, 1.0 / lit.size))
    return lit, sub


def stack_path_colours(pcs: list[PathColours]) -> PathColours:
    """The path colours of several lamps' bases as one basis (each lamp's functions in turn),
    for pixels lit by several kinds of light, each along its own paths (t_p the kinds'
    coefficients side by side): the same u drives every kind's estimate, so their
    cross-covariances count."""
    if len(pcs) == 1:
        return pcs[0]
    n = sum(p.C.shape[0] for p in pcs)
    return PathColours(np.concatenate([p.C for p in pcs]), np.concatenate([p.target for p in pcs]),
                       np.full(n, 1.0 / n), float(np.mean([p.J for p in pcs])))


def one_wavelength_covariance(table, spectrum, basis, step: float = 0.05) -> np.ndarray:
    """The covariance (B, 3, B, 3) of one path's estimate for the hat basis when the path kept
    one of its four wavelengths (a dispersive surface: design §1, the renderer's
    ``TerminateSecondary``): that wavelength is a draw from the table's mixture
    q = (1/4) sum_k p_k, weighted 1 / q, so the estimate for basis function b is
    g_b(λ) = φ_b(λ) E(λ) cmf(λ) / (q(λ) Y_w) and its covariance ∫ q g_b g_c' dλ − c_b c_c'
    (Y_w = ∫ E ȳ: the white surface has Y = 1, as :func:`path_colours`). A trapezoid rule on
    a ``step`` nm grid joined with the lamp's, the table's and the basis' nodes (the lamp's
    narrow lines are resolved by their own nodes). ``spectrum`` may be a list of lamps: the covariance of
    their stacked bases (:func:`stack_path_colours`), one wavelength drawn for all of them."""
    spectra = list(spectrum) if isinstance(spectrum, (list, tuple)) else [spectrum]
    lo, hi = float(table.grid[0]), float(table.grid[-1])
    bwl = np.asarray(basis.wavelengths, dtype=np.float64)
    lam = np.unique(np.concatenate([np.arange(lo, hi, step), [hi], np.asarray(table.grid, np.float64), bwl,
                                    *(np.asarray(sp.wavelengths, dtype=np.float64) for sp in spectra)]))
    lam = lam[(lam >= lo) & (lam <= hi)]
    q = np.mean([np.interp(lam, table.grid, p) for p in np.asarray(table.pdfs, dtype=np.float64)], axis=0)
    w = np.zeros_like(lam)  # trapezoid weights
    w[1:] += 0.5 * np.diff(lam)
    w[:-1] += 0.5 * np.diff(lam)
    G = np.concatenate([_one_wavelength_terms(lam, w, q, sp, basis) for sp in spectra])  # (J*B*3, L)
    # Second moment ∫ q g g' = Σ w q g g'.
    second = (G * (w * q)[None, :]) @ G.T
    mean = (G * (w * q)[None, :]).sum(axis=1)
    n = G.shape[0] // 3
    return (second - np.outer(mean, mean)).reshape(n, 3, n, 3)


def _one_wavelength_terms(lam: np.ndarray, w: np.ndarray, q: np.ndarray, spectrum, basis) -> np.ndarray:
    """g_b,i(λ) = φ_b(λ) cmf_i(λ) E(λ) / (q(λ) Y_w) on ``lam`` (B*3, L) for one lamp
    (:func:`one_wavelength_covariance`; ``w`` the trapezoid weights of ``lam``)."""
    from wavelength_pdf.colorimetry import cmfs

    lo, hi = float(lam[0]), float(lam[-1])
    swl = np.asarray(spectrum.wavelengths, dtype=np.float64)
    E = np.interp(lam, swl, np.asarray(spectrum.values, dtype=np.float64), left=0.0, right=0.0)
    cwl, cval = cmfs()
    cmf = np.stack([np.interp(lam, cwl, cval[:, i], left=0.0, right=0.0) for i in range(3)], axis=1)
    phi = np.stack([np.interp(lam, basis.wavelengths, v) for v in np.asarray(basis.values, dtype=np.float64)])
    yw = float(np.sum(w * E * cmf[:, 1]))
    if not yw > 0:
        raise ValueError(f"{spectrum.name}: no luminance in {lo:g}-{hi:g} nm")
    emits = E > 0
    if np.any(emits & ~(q > 0)):
        raise ValueError(f"the table does not cover {spectrum.name}: q = 0 where the lamp emits")
    f = np.where(emits, E / np.where(q > 0, q, 1.0), 0.0) / yw
    return (phi[:, None, :] * cmf.T[None, :, :] * f[None, None, :]).reshape(-1, lam.size)


def pixel_de2(pc: PathColours, t: np.ndarray, spp: int, pixel_sampler: str = "sobol",
              metric: str = "de2000", incoherence: np.ndarray | None = None,
              terminated: np.ndarray | None = None, one_wavelength: np.ndarray | None = None,
              spread: np.ndarray | None = None,
              cells: Sequence[tuple[tuple[int, int], np.ndarray]] | None = None) -> np.ndarray:
    """Per pixel, the linearised squared error of its mean of ``spp`` samples (the
    ``covariance`` candidate) for pixels whose spectrum is T_p = sum_b t[p, b] φ_b: ``pc`` is
    the table's path colours for the basis of :func:`hat_basis` (K = B). A pixel's colour is
    t_p · target, its estimate t_p · C(u), so the mean's covariance is the quadratic form
    t_p' M t_p of the basis' cross-covariances (:func:`basis_covariance`), formed once.

    ``incoherence`` (P,): each pixel's relative variance r_p of its paths' magnitude from one
    sample to the next (0: every sample of the pixel sees the same path spectrum, as a directly
    lit patch does). A sample's estimate is a·C(u) with a independent of u, and the variance
    of the mean of N is E[a]^2 (Cov_strat + r Cov_u(C) / N) + Var(a) c c' / N: the last term is
    the path noise (the benchmark's floor), the middle one the wavelength noise that the
    pixel's stratification of u cannot remove (with independent u, (1 + r) Cov_u(C) / N).
    r is capped at N (the linearisation's limit: below).

    ``spread`` (P, B, B): each pixel's spread S_p (:func:`wavelength_pdf.evaluation.transfer.spread`),
    the covariance of the spectra its samples see (a patch's edge: two spectra, not one
    spectrum of varying magnitude). It takes the place of r t_p t_p' in the middle term, which
    is its case of one spectrum: sum_bc S_bc Cov_u(C_b, C_c) / N, its relative size capped at
    N as r is.

    ``cells`` (((i, j), V_ij), ...), each V_ij (P, B, B) the part of the spread between the
    pixel's 2^i x 2^j cells of equal filter weight along y and x
    (:func:`.evaluation.transfer.cell_spread_of`), for every i, j up to some L but (0, 0) and
    (L, L): for a render with ``pbrt --wavelength-net``, which draws u together with the film
    position (design §5.2) as a (1, m, 3)-net, so that the samples in a cell have stratified u
    among themselves. Each level's part then takes the covariance of C(u) within 2^k strata,
    k = m - 1 - i - j, in place of Cov_u(C) (:func:`_net_levels`); ``spread`` is needed with it.

    ``terminated`` (P,): the share of each pixel's light carried by paths that kept one
    wavelength (a dispersive surface), with ``one_wavelength`` the basis' covariance of such a
    path (:func:`one_wavelength_covariance`). Those paths' share s of the colour is estimated
    from independent draws of the mixture, the rest as above: the covariance is
    (1 − s)² (stratified part) + s² (1 + r) one_wavelength / N (the two parts taken as
    independent).

    Units: a white surface lit by the lamp has Y = 1, Lab relative to D65 at Y = 1 (the
    benchmark's image units, when t is scaled so: :mod:`.evaluation.transfer`).

    Returns
    -------
    (P,) array
        Each pixel's expected squared CIEDE2000 (``metric='lab'``: Lab distance).
    """
    B = pc.C.shape[0]
    t = np.atleast_2d(np.asarray(t, dtype=np.float64))
    if t.shape[1] != B:
        raise ValueError(f"t has {t.shape[1]} coefficients per pixel, the basis {B}")

    def quad(M):
        return np.einsum("pb,bicj,pc->pij", t, M, t, optimize=True)

    def per_pixel(name, v, hi=np.inf):
        v = np.asarray(v, dtype=np.float64)
        if v.shape != (t.shape[0],) or np.any(~np.isfinite(v)) or np.any(v < 0) or np.any(v > hi):
            raise ValueError(f"{name} must be {t.shape[0]} finite values in [0, {hi:g}]")
        return v[:, None, None]

    cov = quad(basis_covariance(pc, spp, pixel_sampler))
    # Capped at N: beyond it the mean of N samples is ruled by paths rarer than one in N, its
    # relative variance r / N exceeds 1, and Lab's cube root no longer follows the linearised
    # error (which would grow with r without bound while the CIEDE2000 of such pixels does not).
    r = np.minimum(per_pixel("incoherence", incoherence), spp) if incoherence is not None else 0.0
    spread_cov = 0.0
    if cells is not None and spread is None:
        raise ValueError("cells are parts of a spread: give the spread too")
    if spread is not None:
        cap = _spread_cap(spread, t, spp, pc.target[:, 1])
        spread_cov = sum(np.einsum("pbc,bicj->pij", cap * part, level_covariance(pc, n, spp), optimize=True)
                         for part, n in _net_levels(np.asarray(spread, dtype=np.float64), cells, spp,
                                                    pc.target[:, 1], pixel_sampler))
    elif incoherence is not None:
        cov = cov + r * quad(basis_covariance(pc, spp, "independent"))
    share = 0.0
    if terminated is not None:
        if one_wavelength is None or np.shape(one_wavelength) != (B, 3, B, 3):
            raise ValueError(f"terminated needs one_wavelength, the basis' ({B}, 3, {B}, 3) covariance")
        share = per_pixel("terminated", terminated, 1.0)
        cov = (1.0 - share) ** 2 * cov + share ** 2 * (1.0 + r) * quad(np.asarray(one_wavelength)) / spp
    xyz = t @ pc.target
    if spread is None:
        return lab_quadratic(xyz, cov, metric)
    jac = _lab_jacobians(xyz)  # once, for both terms
    de2 = lab_quadratic(xyz, cov, metric, jac=jac)
    # A measured spread is noisy, its covariance indefinite in some pixels: measured linearly
    # (the objective's form, tr(A C)), its noise cancels in the mean over pixels, where
    # lab_quadratic's clipping of negative variances would bias it upwards.
    A = np.swapaxes(jac, 1, 2) @ jac if metric == "lab" else xyz_metrics(xyz, jac=jac)
    return de2 + np.einsum("pij,pij->p", A, (1.0 - share) ** 2 * spread_cov)


def kinds_spread(t: np.ndarray, y: np.ndarray, kind_of: np.ndarray,
                 incoherence: np.ndarray | None = None) -> np.ndarray:
    """The spread (P, B, B) of pixels lit by several kinds of light along their own paths
    (design §6.8), ``t`` (P, B) their coefficients with column b of kind ``kind_of[b]`` and
    luminance ``y[b]`` (t_p · y is pixel p's Y). A sample of the pixel carries the light of one
    kind, not of their mixture: next-event estimation picks one light, and the light sampler
    picks it in proportion to its contribution, so kind j with probability q_pj, its share of
    the pixel's luminance. The sample's spectrum is then a t_pj / q_pj (t_pj the pixel's
    coefficients of kind j, zero elsewhere; a its magnitude, E a = 1 and E a² = 1 + r_p), whose
    covariance over the samples is

        S_p = (1 + r_p) Σ_j t_pj t_pjᵀ / q_pj − t_p t_pᵀ,

    r_p t_p t_pᵀ for one kind. The pixel's stratification of u cannot cancel what changes from
    one sample to the next, so this, not r_p t_p t_pᵀ, is what it leaves (:func:`pixel_de2`)."""
    t = np.atleast_2d(np.asarray(t, dtype=np.float64))
    y = np.asarray(y, dtype=np.float64)
    kind_of = np.asarray(kind_of)
    Pn, B = t.shape
    if y.shape != (B,) or kind_of.shape != (B,):
        raise ValueError(f"y and kind_of must give each of the {B} columns its luminance and kind")
    r = np.zeros(Pn) if incoherence is None else np.asarray(incoherence, dtype=np.float64)
    Y = np.stack([t[:, kind_of == j] @ y[kind_of == j] for j in np.unique(kind_of)], axis=1)  # (P, J)
    total = Y.sum(axis=1, keepdims=True)
    q = np.divide(Y, total, out=np.zeros_like(Y), where=total > 0)
    S = -t[:, :, None] * t[:, None, :]
    for i, j in enumerate(np.unique(kind_of)):
        cols = np.flatnonzero(kind_of == j)
        blk = t[:, cols]
        w = np.divide(1.0 + r, q[:, i], out=np.zeros(Pn), where=q[:, i] > 0)
        S[:, cols[:, None], cols[None, :]] += w[:, None, None] * blk[:, :, None] * blk[:, None, :]
    return S


def _spread_cap(spread: np.ndarray, t: np.ndarray, spp: int, y: np.ndarray) -> np.ndarray:
    """(P, 1, 1): the factor that scales each pixel's spread (P, B, B), checked, down where the
    relative variance of its samples' luminance, y' S y / (t · y)^2 (r for one spectrum; y the
    basis' luminances), exceeds N (:func:`pixel_de2`). In luminance, not in the coefficients,
    so that the cap does not depend on the basis functions' units (a kinds' problem scales
    each kind's)."""
    S = np.asarray(spread, dtype=np.float64)
    P, B = t.shape
    if S.shape != (P, B, B) or not np.all(np.isfinite(S)):
        raise ValueError(f"spread must be ({P}, {B}, {B}) finite values, not {S.shape}")
    y = np.asarray(y, dtype=np.float64)
    rel = np.einsum("b,pbc,c->p", y, S, y) / np.maximum((t @ y) ** 2, 1e-300)
    return np.minimum(1.0, spp / np.maximum(rel, 1e-300))[:, None, None]


def _capped_spread(spread: np.ndarray, t: np.ndarray, spp: int, y: np.ndarray) -> np.ndarray:
    """The spread (P, B, B) capped as :func:`_spread_cap` says."""
    return np.asarray(spread, dtype=np.float64) * _spread_cap(spread, t, spp, y)


def _net_levels(spread: np.ndarray, cells, spp: int, y: np.ndarray, pixel_sampler: str = "sobol"):
    """[(part (P, B, B), n)]: the spread cut into the parts of :func:`pixel_de2`'s ``cells``,
    each with the number n of equal strata of u within which C(u)'s covariance is left
    (:func:`level_covariance`; None: unstratified, Cov_u(C) / N); without cells, the whole
    spread, unstratified.

    ``cells`` gives V(i, j), the spread between a pixel's 2^i x 2^j cells, for every i, j up to
    some L but (0, 0) (none) and (L, L) (the spread itself). The part of level (i, j) exactly,
    V(i, j) - V(i-1, j) - V(i, j-1) + V(i-1, j-1), times a function of u varies over boxes of
    2^i x 2^j x 2^k; a scrambled (t, m, 3)-net integrates every such part with i + j + k <= m - t
    exactly (Owen's gain coefficients vanish there), so with t = 1 only the part of C(u) within
    2^k strata, k = m - 1 - i - j, is left: Cov_u(C) less the covariance of the strata's means,
    2^k times :func:`basis_covariance` at 2^k, over N. The finest level (L, L) holds each
    path's own difference and stays unstratified.

    A level's part is a difference of four noisy measures: its own spectral shape has
    directions of negative variance (on the ColorChecker down to -8 % of the spread's trace at
    the finest levels), which a table's covariance can weight more than the rest, so that
    whole predictions came out negative. So each stratified level counts as its share of the
    pixels' spread in luminance, over all the pixels given (sum_p y' part_p y / sum_p y' S_p y,
    ``y`` the basis' luminances, clipped to [0, 1], the shares to a sum of at most 1), times
    each pixel's spread, and the rest of it as unstratified: the weights do not depend on any
    one pixel's noise, which then cancels in the mean over the pixels as without cells (a
    share per pixel, tried first, left 13 of 686 predictions on the ColorChecker negative)."""
    if cells is None:
        return [(spread, None)]
    if pixel_sampler != "sobol":
        raise ValueError("cells model the low-discrepancy pixel sampler with pbrt --wavelength-net")
    V = {}
    for key, v in cells:
        v = np.asarray(v, dtype=np.float64)
        if v.shape != spread.shape or not np.all(np.isfinite(v)):
            raise ValueError(f"each of the cells must be a finite {spread.shape} array")
        V[tuple(key)] = v
    L = max((max(k) for k in V), default=0)
    if L < 1 or set(V) != {(i, j) for i in range(L + 1) for j in range(L + 1) if 0 < i + j < 2 * L}:
        raise ValueError("cells must be every level (i, j) up to some L >= 1 but (0, 0) and (L, L)")
    m = int(spp).bit_length() - 1
    y = np.asarray(y, dtype=np.float64)

    def lum(v):  # a spread's luminance, summed over the pixels: the only figure of it a share needs
        return float(np.einsum("b,pbc,c->", y, v, y))

    # The inclusion-exclusion is linear: taken on each level's luminance, not its (P, B, B) arrays.
    Y = {key: lum(v) for key, v in V.items()}
    Y[(0, 0)] = 0.0  # the pixel itself: no spread between cells (level (L, L) is the rest's)
    whole = lum(spread)

    def at(i, j):
        return Y[(i, j)] if i >= 0 and j >= 0 else 0.0

    shares = {}
    for (i, j) in sorted(Y):
        k = m - 1 - i - j
        if (i, j) == (0, 0) or k < 1:
            continue  # unstratified: with the rest
        part = at(i, j) - at(i - 1, j) - at(i, j - 1) + at(i - 1, j - 1)
        ratio = part / whole if whole > 0 else 0.0
        shares[2 ** k] = shares.get(2 ** k, 0.0) + min(max(ratio, 0.0), 1.0)
    total = sum(shares.values())
    scale = 1.0 / max(total, 1.0)
    parts = [(spread * (share * scale), n) for n, share in sorted(shares.items())]
    return [*parts, (spread * (1.0 - total * scale), None)]


def level_covariance(pc: PathColours, n: int | None, spp: int) -> np.ndarray:
    """(B, 3, B, 3): C(u)'s covariance within n equal strata of u (averaged over them) over N =
    ``spp``, n times :func:`basis_covariance` at n; None: the whole covariance over N. A part
    of a pixel's spread that the net integrates over every coarser stratum (:func:`_net_levels`)
    adds its quadratic form with this."""
    if n is None:
        return basis_covariance(pc, spp, "independent")
    return (n / spp) * basis_covariance(pc, n, "sobol")


def path_de2(xyz: np.ndarray, incoherence: np.ndarray, spp: int, metric: str = "de2000") -> np.ndarray:
    """Per pixel, the linearised squared error of the path noise alone (the benchmark's floor,
    predicted): the mean of N samples a·c has the covariance r c c' / N (r the pixel's
    incoherence, :func:`pixel_de2`, capped at N as there)."""
    xyz = np.atleast_2d(np.asarray(xyz, dtype=np.float64))
    r = np.minimum(np.asarray(incoherence, dtype=np.float64), spp)
    if r.shape != (xyz.shape[0],) or np.any(~np.isfinite(r)) or np.any(r < 0):
        raise ValueError(f"incoherence must be {xyz.shape[0]} finite values >= 0")
    cov = (r / spp)[:, None, None] * xyz[:, :, None] * xyz[:, None, :]
    return lab_quadratic(xyz, cov, metric)


def lab_quadratic(xyz: np.ndarray, cov: np.ndarray, metric: str = "de2000",
                  jac: np.ndarray | None = None) -> np.ndarray:
    """Per pixel, E[d(Lab(xyz + e), Lab(xyz))^2] for a zero-mean error e of covariance ``cov``
    (P, 3, 3), linearised: the covariance mapped to Lab by the Jacobian at each colour and
    measured by CIEDE2000's local quadratic form along its principal axes (as
    :func:`expected_quadratic`, vectorised), or by Lab distance (``metric='lab'``). ``jac``:
    :func:`_lab_jacobians` at ``xyz``, where the caller has it already."""
    import colour

    white = _white_xy()
    jac = _lab_jacobians(xyz) if jac is None else jac
    cov_lab = jac @ cov @ np.swapaxes(jac, 1, 2)
    s, V = np.linalg.eigh(0.5 * (cov_lab + np.swapaxes(cov_lab, 1, 2)))
    s = np.clip(s, 0.0, None)
    if metric == "lab":
        return s.sum(axis=1)
    if metric != "de2000":
        raise ValueError(f"metric must be 'de2000' or 'lab', not {metric!r}")
    lab_c = np.asarray(colour.XYZ_to_Lab(xyz, white))
    eps = 1e-4  # as expected_quadratic: small against any colour difference
    total = np.zeros(xyz.shape[0])
    for i in range(3):
        v = V[:, :, i]
        q = 0.5 * sum(delta_e2000(lab_c + sgn * eps * v, lab_c) ** 2 for sgn in (1.0, -1.0)) / eps ** 2
        total += s[:, i] * q
    return total


def _lab_jacobians(xyz: np.ndarray) -> np.ndarray:
    """d Lab / d XYZ (P, 3 Lab, 3 XYZ) at each colour by central differences."""
    import colour

    white = _white_xy()
    h = 1e-6 * np.maximum(np.abs(xyz).max(axis=1, keepdims=True), 1e-12)
    return np.stack([(colour.XYZ_to_Lab(xyz + h * e, white) - colour.XYZ_to_Lab(xyz - h * e, white)) / (2 * h)
                     for e in np.eye(3)], axis=-1)


def xyz_metrics(xyz: np.ndarray, jac: np.ndarray | None = None) -> np.ndarray:
    """CIEDE2000's local quadratic form in XYZ at each colour (P, 3, 3): A = Jl' G Jl, so that
    E[CIEDE2000(xyz + e, xyz)^2] ~ tr(A Cov(e)) for a small error e, G the form in Lab
    (:func:`wavelength_pdf.problem.de2000_metric`, the ``stratified`` objective's): it is
    :func:`lab_quadratic`'s form as a matrix, for objectives that are linear in a covariance
    (:func:`pixel_weights`). ``jac``: :func:`_lab_jacobians` at ``xyz``, where the caller has
    it already."""
    import colour

    from wavelength_pdf.problem import de2000_metric

    xyz = np.atleast_2d(np.asarray(xyz, dtype=np.float64))
    jac = _lab_jacobians(xyz) if jac is None else jac
    return np.swapaxes(jac, 1, 2) @ de2000_metric(colour.XYZ_to_Lab(xyz, _white_xy())) @ jac


def pixel_weights(target: np.ndarray, t: np.ndarray, spp: int, incoherence: np.ndarray | None = None,
                  terminated: np.ndarray | None = None, spread: np.ndarray | None = None,
                  cells: Sequence[tuple[tuple[int, int], np.ndarray]] | None = None) -> np.ndarray:
    """The weights (3, B*3, B*3) with which :func:`pixel_de2`'s mean over the pixels is linear in
    the basis' covariances (design §4.6, ``pixels``): W_s, W_i, W_1 with

        mean_p de2_p = tr(W_s M_s) + tr(W_i M_i) + tr(W_1 O),

    M_s the stratified and M_i the independent covariance of a pixel's mean of ``spp`` samples
    (:func:`basis_covariance`), O one path's covariance when it keeps one wavelength
    (:func:`one_wavelength_covariance`), each flattened colour-major (b, channel). Each pixel
    contributes t_p t_p' ⊗ A_p (A_p, :func:`xyz_metrics` at its colour t_p · target) times
    (1 − s)², (1 − s)² r and s² (1 + r) / N, r its incoherence capped at N and s its
    dispersed share, as in :func:`pixel_de2`; with ``spread``, W_i's pixel term is
    (1 − s)² S_p ⊗ A_p instead. With ``cells`` too (:func:`pixel_de2`) the spread's parts
    that the net stratifies go to weights of their own: the result is then (2 + m, B*3, B*3)
    for N = 2^m, entry 2 + k (k = 1 … m − 1) weighting C(u)'s covariance within 2^k strata,
    N · :func:`level_covariance` at 2^k (0 where no part falls). The metric at each pixel's
    colour depends on
    the lamp and the scene, not on the table, so an optimizer can minimise the image's
    predicted error through three fixed matrices, whatever the number of pixels."""
    t = np.atleast_2d(np.asarray(t, dtype=np.float64))
    target = np.asarray(target, dtype=np.float64)
    P, B = t.shape
    if target.shape != (B, 3):
        raise ValueError(f"target must be ({B}, 3), the basis' colours, not {target.shape}")
    if P == 0:
        raise ValueError("no pixels to weight")
    r = np.zeros(P) if incoherence is None else np.minimum(np.asarray(incoherence, dtype=np.float64), spp)
    s = np.zeros(P) if terminated is None else np.asarray(terminated, dtype=np.float64)
    if r.shape != (P,) or s.shape != (P,) or not (np.all(np.isfinite(r)) and np.all(r >= 0)
                                                  and np.all((s >= 0) & (s <= 1))):
        raise ValueError(f"incoherence and terminated must be {P} finite values (>= 0, and in [0, 1])")
    A = xyz_metrics(t @ target)

    def outer(w):
        return np.einsum("p,pb,pc,pij->bicj", w / P, t, t, A, optimize=True)

    def spread_weight(part):
        return np.einsum("p,pbc,pij->bicj", (1 - s) ** 2 / P, part, A, optimize=True)

    # The unstratified term: each pixel's spread (what the net does not stratify of it), or its
    # one spectrum's r t t'.
    levels = {}
    if spread is not None:
        cap = _spread_cap(spread, t, spp, target[:, 1])
        for part, n in _net_levels(np.asarray(spread, dtype=np.float64), cells, spp, target[:, 1]):
            levels[n] = levels.get(n, 0.0) + spread_weight(cap * part)
    middle = levels.pop(None, 0.0) if spread is not None else outer((1 - s) ** 2 * r)
    W = [outer((1 - s) ** 2), np.broadcast_to(middle, (B, 3, B, 3)), outer(s ** 2 * (1 + r) / spp)]
    if cells is not None:
        W += [levels.get(2 ** k, np.zeros((B, 3, B, 3))) for k in range(1, int(spp).bit_length() - 1)]
    return np.stack([w.reshape(B * 3, B * 3) for w in W])


def j_squared(pc: PathColours, spp: int, pixel_sampler: str = "sobol") -> float:
    """Candidate (a): J^2, today's objective (design §4.1) in squared-error units; the same
    for every spp and pixel sampler (J does not know them)."""
    return pc.J ** 2


#: The candidates by name: each maps (path colours, spp, pixel sampler) to a predicted mean
#: squared CIEDE2000 of a pixel.
CANDIDATES: dict[str, Callable[[PathColours, int, str], float]] = {
    "J": j_squared,
    "stratified": stratified_de2,
    "stratified-de": lambda pc, spp, ps="sobol": stratified_de2(pc, spp, ps, power=1),
    "covariance": covariance_de2,
    "covariance-lab": lambda pc, spp, ps="sobol": covariance_de2(pc, spp, ps, metric="lab"),
}


def predict(candidate: str, table, spectrum, spp: int, pixel_sampler: str = "sobol",
            reflectances=None) -> float:
    """The predicted mean squared CIEDE2000 of a pixel rendered with ``table`` under
    ``spectrum`` at ``spp`` (one of :data:`CANDIDATES`)."""
    if candidate not in CANDIDATES:
        raise ValueError(f"unknown candidate {candidate!r}; one of {', '.join(CANDIDATES)}")
    return CANDIDATES[candidate](path_colours(table, spectrum, reflectances), spp, pixel_sampler)
