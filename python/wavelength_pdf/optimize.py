"""Public entry point: optimize the four wavelength densities for one spectrum.

    result = optimize_spectrum(load_spectrum("cie:FL11"))
    if result.accepted:
        write_table("fl11.csv", result.to_table())

The result (:class:`wavelength_pdf.result.Result`) carries J of the optimized table at two
u-resolutions, J of stratified uniform sampling and of the initialization (design §4), and
the estimator's health for the result and for the initialization; ``accepted`` is
:func:`wavelength_pdf.health.rejection`'s verdict (bias at most 1e-6, no channel's std worse
than the initialization's, J no worse than stratified uniform sampling's).

The work runs in float64 (scoped: JAX's global settings are left as they were) and with one
BLAS thread; the command line also fixes XLA's thread count (:mod:`wavelength_pdf.threads`),
so that the same input and seed give the same table on any number of cores.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING, Callable

import numpy as np

from . import grids, health as health_mod, init as init_mod, objective as objective_mod, uniform
from .budget import Budget
from .compile_cache import enable_compilation_cache
from .model import DEFAULT_GRID, normalize_density
from .precision import float64
from .problem import (DEFAULT_OBJECTIVE_SPP, Problem, check_objective, make_problem, objective_label, with_objective,
                      with_share)
from .quadrature import ORDER_FINE
from .result import Result
from .solvers import DEFAULT_SOLVER, REFINE_EVALUATIONS, SOLVERS, Solver, Start, initialization_result, refine
from .table import Table
from .threads import single_threaded_blas

if TYPE_CHECKING:  # annotations only: no import cost at run time
    from .reflectances import ReflectanceSet
    from .spectra import Spectrum

__all__ = ["Result", "optimize_spectrum", "evaluate_table", "evaluation_budget", "starting_table",
           "DEFAULT_GRID", "SOLVERS"]


def _solver(name: str) -> Solver:
    if name not in SOLVERS:
        raise ValueError(f"unknown solver {name!r}; choose one of: {', '.join(SOLVERS)}")
    return SOLVERS[name]


def _evaluations(solver: Solver, solver_options: dict | None) -> tuple[int, dict]:
    """The evaluation count (``max_evals`` of the options, else the solver's own) and the
    solver's other options."""
    options = dict(solver_options or {})
    return int(options.pop("max_evals", solver.max_evaluations)), options


def evaluation_budget(solver: str = DEFAULT_SOLVER, grid: np.ndarray | str = "auto",
                      solver_options: dict | None = None, objective: str = "J") -> int:
    """Most objective evaluations :func:`optimize_spectrum` spends (for progress bars)."""
    n = _evaluations(_solver(solver), solver_options)[0]
    return n + (0 if objective == "J" else _refine_evaluations(n))


def _refine_evaluations(search: int) -> int:
    """The polish's evaluations after a search of ``search`` (design §4.6): at most as many."""
    return min(REFINE_EVALUATIONS, search)


def _grid_and_problem(spectrum, grid: np.ndarray | str, reflectances) -> tuple[np.ndarray, Problem]:
    """The table grid and the problem on it. "auto" chooses the grid on the lamp's problem
    on the default grid (``grids.auto_grid``), which is already the problem to solve when
    that grid is kept and J has no surface colours (smooth lamps): it is built once."""
    if isinstance(grid, str):
        if grid != "auto":
            raise ValueError(f"grid must be an array of wavelengths or 'auto', not {grid!r}")
        lamp = make_problem(spectrum, DEFAULT_GRID)
        grid = grids.auto_grid(lamp, DEFAULT_GRID)
        if reflectances is None and np.array_equal(grid, DEFAULT_GRID):
            return grid, lamp
    grid = np.asarray(grid, dtype=np.float64)
    return grid, make_problem(spectrum, grid, reflectances)


@float64
def optimize_spectrum(
    spectrum: Spectrum,
    *,
    grid: np.ndarray | str = "auto",
    solver: str = DEFAULT_SOLVER,
    seed: int = 0,
    progress: Callable[[int, float], None] | None = None,
    max_seconds: float | None = None,
    solver_options: dict | None = None,
    reflectances: ReflectanceSet | None = None,
    objective: str = "J",
    objective_spp: int = DEFAULT_OBJECTIVE_SPP,
) -> Result:
    """Find four wavelength densities on ``grid`` that minimize J for ``spectrum``.

    Parameters
    ----------
    spectrum : wavelength_pdf.spectra.Spectrum
        The lamp, at its own resolution.
    grid : (M+1,) array (nm), or "auto"
        Table nodes (default 380..780 nm in 5 nm steps). "auto": the default grid for
        smooth spectra; for line lamps (``grids.is_spiky``) the default grid refined
        at the lines' edges and peaks (``grids.auto_grid``).
    solver : str
        A name in ``solvers.SOLVERS``.
    seed : int
        Seed of the random starting points (same input and seed, same table).
    progress : callable(step, J), optional
        Called after every objective evaluation with the best J so far.
    max_seconds : float, optional
        Wall-time cap of the call, counted from its start: choosing the grid, compiling and
        evaluating the figures every result reports (J of the initialization and of
        stratified uniform sampling, their health) come first, the search gets what is left
        (none: the initialization is the result) and stops at the cap; after it, only the
        figures of the table found are computed (a fraction of a second once compiled). A
        compilation under way cannot be cut short: the search only starts when more time
        is left than the reference figures took, about what compiling it takes. The
        solvers normally stop on an evaluation budget, which keeps results reproducible; a
        time cap that bites makes them depend on the machine's speed. A capped result is
        judged like any other: it is never accepted when its J is worse than stratified
        uniform sampling's.
    solver_options : dict, optional
        Extra keyword arguments for the solver (e.g. ``{"max_evals": 300}``, the evaluation
        budget). ``multistage`` follows a result above ``solvers.SECOND_SEARCH_ABOVE`` x
        J_uniform with a second search with more starts kept and
        ``solvers.SECOND_SEARCH_BUDGET`` times the budget; the better accepted table wins.
    reflectances : wavelength_pdf.reflectances.ReflectanceSet, optional
        Surface colours (design §4.5): J is the weighted mean of every colour's J, and the
        health rules hold for every colour. The grid ("auto") is still chosen for the lamp.
    objective, objective_spp : str, int
        What to minimize (design §4.6): ``"J"`` (§4.1, the default) or ``"stratified"``,
        the linearised CIEDE2000 of a pixel of ``objective_spp`` stratified samples. Every
        J of the result (of the table, the start and stratified uniform sampling, and the
        rule that accepts it) is then that objective's value.

    Raises
    ------
    ValueError
        Unknown solver (or one whose optional package is missing), bad grid, unknown
        objective or spp, or a spectrum without power in the grid range.
    """
    check_objective(objective, objective_spp)
    run_solver = _solver(solver)
    run_solver.check_available()
    t0 = time.monotonic()
    if max_seconds is not None and not (math.isfinite(max_seconds) and max_seconds > 0):
        raise ValueError(f"max_seconds must be a finite number of seconds > 0, got {max_seconds!r}")
    max_evaluations, options = _evaluations(run_solver, solver_options)
    budget = Budget.starting(max_evaluations, max_seconds, t0)
    enable_compilation_cache()
    grid, problem = _grid_and_problem(spectrum, grid, reflectances)
    # The reference figures every result reports, before the search: under a time cap
    # their compiling counts against it, and the search gets what is left.
    P0 = init_mod.equal_mass_partition(problem)
    t_figures = time.monotonic()
    start = Start.of(problem, P0)
    figures_took = time.monotonic() - t_figures
    left = budget.seconds_left()
    # A compilation cannot be cut short, and the search's (its objective with gradient)
    # takes about as long as these figures' did, cached or not: it only starts if that
    # much time is left, so a cap spent compiling is not overrun by a whole compilation.
    if left is not None and left <= figures_took:
        run = initialization_result(start, f"{solver}: not started: {max(left, 0.0):.2g} s of the "
                                           f"time cap of {max_seconds:g} s were left after choosing "
                                           "the grid and compiling, less than starting the search takes")
    else:
        with single_threaded_blas():
            run = run_solver(start, budget, seed=seed, progress=progress, **options)
    if objective != "J":
        # J's search finds the basin, a polish by the chosen objective its bottom
        # (``solvers.refine``); every figure of the result is that objective's.
        problem = with_objective(problem, objective, objective_spp)
        start = start.standing_for(problem)
        with single_threaded_blas():
            run = refine(start, run, budget.with_evaluations(_refine_evaluations(max_evaluations)),
                         progress=progress)
    return _judged(problem, start, run, grid, t0, name=getattr(spectrum, "name", ""),
                   source=_source(spectrum, reflectances), solver=solver, seed=seed,
                   objective=objective_label(objective, objective_spp))


def _judged(problem, start: Start, run, grid: np.ndarray, t0: float, **record) -> Result:
    """The search's table judged by §4.4's rules against its start, in ``problem``'s
    objective, with the seconds since ``t0``; ``record``: name, source, solver, seed,
    objective."""
    result = Result.judge(
        Table(grid=grid.copy(), pdfs=run.P), J=run.J, J_fine=objective_mod.J(problem, run.P, ORDER_FINE),
        J_uniform=start.J_uniform, J_init=start.J,
        health=run.health if run.health is not None else health_mod.health(problem, run.P),
        health_init=start.health, history=list(run.history), message=run.message, **record)
    result.seconds = time.monotonic() - t0
    return result


def kinds_basis(spectra: list, hats, grid: np.ndarray):
    """One lamp and one set of surfaces standing for pixels lit by several kinds of light, each
    along its own paths (design §4.6), so that one problem of :func:`make_problem` (which takes
    one spectrum) scores them: the lamp is the kinds' sum m = sum_j E_j and surface (j, b) is
    φ_b E_j / m (0 where m is), so that under m it returns E_j φ_b, kind j's light on hat
    function b, at every node of the kinds, the hats, the CMFs and the grid. Returns (lamp,
    surfaces, their indices j B + b among the kinds' stacked hats (those each kind lights), each
    surface's luminance under its own kind relative to E_j's white, as the prediction has it: a
    problem's colours are relative to its own lamp's white, so a pixel's t_pjb is scaled by this
    over the problem's)."""
    from .colorimetry import cmfs
    from .predict import lit_basis
    from .reflectances import ReflectanceSet
    from .spectra import Spectrum

    lo, hi = float(grid[0]), float(grid[-1])
    B = len(hats.labels)
    hw = np.asarray(hats.wavelengths, dtype=np.float64)
    # Every node a kind's own problem would have (the CMFs', the grid's, the hats'), so that the
    # products E_j φ_b are taken at the same nodes as in the prediction, not interpolated.
    cw = cmfs()[0]
    nodes = [hw[(hw >= lo) & (hw <= hi)], cw[(cw >= lo) & (cw <= hi)], np.asarray(grid, dtype=np.float64)]
    for sp in spectra:
        w = np.asarray(sp.wavelengths, dtype=np.float64)
        nodes.append(w[(w > lo) & (w < hi)])
    nodes = np.unique(np.concatenate(nodes))
    E = np.stack([np.interp(nodes, sp.wavelengths, sp.values, left=0.0, right=0.0) for sp in spectra])
    m = E.sum(axis=0)
    share = np.divide(E, m, out=np.zeros_like(E), where=m > 0)
    phi = np.stack([np.interp(nodes, hw, v) for v in np.asarray(hats.values, dtype=np.float64)])
    values, labels, index, own_y = [], [], [], []
    for j, sp in enumerate(spectra):
        lit, sub = lit_basis(sp, hats, lo, hi)
        own = make_problem(sp, grid, sub).c  # kind j's colours, relative to E_j's white
        values += [phi[b] * share[j] for b in lit]
        labels += [f"kind {j} {hats.labels[b]}" for b in lit]
        index += [j * B + b for b in lit]
        own_y.append(own[:, 1])
    lamp = Spectrum("kinds", f"the sum of {len(spectra)} kinds of light", nodes, m)
    surfaces = ReflectanceSet("kinds", "hat functions under each kind of light", nodes, np.asarray(values),
                              tuple(labels), np.full(len(values), 1.0 / len(values)))
    return lamp, surfaces, np.asarray(index), np.concatenate(own_y)


@float64
def pixels_problem(spectrum, grid: np.ndarray, t: np.ndarray, centres: np.ndarray, spp: int, *,
                   incoherence: np.ndarray | None = None, terminated: np.ndarray | None = None,
                   spread: np.ndarray | None = None, cells=None) -> tuple[Problem, Spectrum]:
    """The ``pixels`` objective's problem (design §4.6) on the table ``grid`` for the pixels of
    :func:`optimize_for_pixels` (its arguments), and the lamp it is built on: ``spectrum``, or
    for several kinds of light their sum (:func:`kinds_basis`)."""
    from .predict import hat_basis, kinds_spread, lit_basis, pixel_weights

    grid = np.asarray(grid, dtype=np.float64)
    centres = np.asarray(centres, dtype=np.float64)
    t = np.atleast_2d(np.asarray(t, dtype=np.float64))
    spectra = list(spectrum) if isinstance(spectrum, (list, tuple)) else [spectrum]
    if t.shape[1] != len(spectra) * centres.size:
        raise ValueError(f"t has {t.shape[1]} coefficients per pixel, the basis {centres.size} centres"
                         + (f" for each of {len(spectra)} kinds of light" if len(spectra) > 1 else ""))
    hats = hat_basis(centres, float(grid[0]), float(grid[-1]))
    if len(spectra) == 1:
        spectrum = spectra[0]
        lit, basis = lit_basis(spectrum, hats, float(grid[0]), float(grid[-1]))
    else:
        if spread is not None or cells is not None:
            raise ValueError("a measured spread is one kind of light's; several kinds have their own (kinds_spread)")
        spectrum, basis, lit, own_y = kinds_basis(spectra, hats, grid)
    problem = make_problem(spectrum, grid, basis)
    if len(spectra) > 1:
        # each kind's colours as the prediction's (the unlit columns are left out below), and
        # each sample carrying one kind's light, as the prediction has it
        t = t * np.bincount(lit, weights=own_y / np.asarray(problem.c)[:, 1], minlength=t.shape[1])
        spread = kinds_spread(t[:, lit], np.asarray(problem.c)[:, 1], lit // centres.size, incoherence)
    elif spread is not None:
        spread = np.asarray(spread, dtype=np.float64)
        if spread.shape != (t.shape[0], centres.size, centres.size):
            raise ValueError(f"spread must be ({t.shape[0]}, {centres.size}, {centres.size}), not {spread.shape}")
        spread = spread[:, lit][:, :, lit]
        if cells is not None:
            cells = tuple((key, np.asarray(c, dtype=np.float64)[:, lit][:, :, lit]) for key, c in cells)
    elif cells is not None:
        raise ValueError("cells are parts of a spread: give the spread too")
    W = pixel_weights(problem.c, t[:, lit], spp, incoherence, terminated, spread, cells)
    problem = with_objective(problem, "pixels", spp, W)
    return problem, spectrum


@float64
def optimize_for_pixels(spectrum: Spectrum, table: Table, t: np.ndarray, centres: np.ndarray, spp: int, *,
                        incoherence: np.ndarray | None = None, terminated: np.ndarray | None = None,
                        spread: np.ndarray | None = None, cells=None, share: tuple[float, Table] | None = None,
                        max_evaluations: int = REFINE_EVALUATIONS,
                        progress: Callable[[int, float], None] | None = None) -> Result:
    """Polish ``table`` (e.g. the lamp's J table, or its emission table) on its own grid for
    the image a scene shows at ``spp``: the ``pixels`` objective (design §4.6), whose value
    is the predicted mean squared CIEDE2000 of the wavelength noise over the pixels whose
    spectral transfers are ``t`` (P, B) at the hat basis' ``centres``
    (:mod:`wavelength_pdf.evaluation.transfer`, in the image's units), with their
    ``incoherence`` and dispersed share ``terminated`` (:func:`wavelength_pdf.predict.pixel_de2`),
    or their ``spread`` (P, B, B) in place of the incoherence, with ``cells`` its parts that
    ``pbrt --wavelength-net`` stratifies (:func:`wavelength_pdf.predict.pixel_de2`). ``spectrum`` may be a list of J
    kinds of light, ``t`` then (P, J B) each pixel's transfers along each kind's own paths side
    by side (:func:`wavelength_pdf.evaluation.transfer.kind_transfers`, as
    :func:`~wavelength_pdf.evaluation.choose.wavelength_error` takes them; :func:`kinds_basis`),
    each pixel's spread then the kinds' (:func:`wavelength_pdf.predict.kinds_spread`).
    ``share``: (S, D), the table is sampled with the share S of the four densities of table D
    mixed into its own (a guiding table's defensive share, design §1.8), and is polished as so
    sampled (:func:`wavelength_pdf.problem.with_share`; D is taken at the table's grid), with no
    channel's std held (below); the result is the unmixed table.

    The search is :func:`wavelength_pdf.solvers.refine`'s polish of the given table, at most
    ``max_evaluations``, and it is never worse than the given table by this objective: that
    table is the result when nothing better passes the health check. The check holds each
    channel's std to the larger of the equal-mass initialization's and the given table's, so
    a table that is itself worse than the initialization in a channel (an emission table
    of a lamp with little blue) can be polished; with a ``share`` it holds no channel's std,
    only the bias. The record's J_init is the equal-mass
    initialization's. The result's J figures are sqrt(N V), V the predicted mean de2
    (:func:`wavelength_pdf.evaluation.choose.wavelength_error`).
    """
    from .solvers import SolverResult

    check_objective("pixels", spp)
    t0 = time.monotonic()
    enable_compilation_cache()
    grid = np.asarray(table.grid, dtype=np.float64)
    problem, spectrum = pixels_problem(spectrum, grid, t, centres, spp, incoherence=incoherence,
                                       terminated=terminated, spread=spread, cells=cells)
    if share is not None:
        S, D = share
        problem = with_share(problem, S, [np.interp(grid, D.grid, d, left=0.0, right=0.0) for d in D.pdfs])
    P_from = normalize_density(grid, table.pdfs)
    given = health_mod.health(problem, P_from)
    if not given.accepted():
        raise ValueError(f"the table to polish is not usable for {getattr(spectrum, 'name', 'the spectrum')}: "
                         f"{given.reason()}")
    initial = Start.of(problem, init_mod.equal_mass_partition(problem))
    # With a share the table's weights are bounded (every density is at least S d_k) and the
    # objective is itself every pixel's variance, so no channel's std on the white surface is
    # held: that guard would keep, say, a sodium-lit table's blue, which its pixels hardly
    # show, at the cost of the colours they do (design §4.6).
    std = np.full_like(given.std, np.inf) if share is not None else np.maximum(initial.health.std, given.std)
    initial = dataclasses.replace(initial, health=dataclasses.replace(initial.health, std=std))
    # The search starts from, and falls back to, the given table.
    start = dataclasses.replace(initial, P=P_from, J=objective_mod.J(problem, P_from))
    found = SolverResult(P=P_from, J=start.J, health=given, message="from the given table")
    with single_threaded_blas():
        run = refine(start, found, Budget.starting(max_evaluations, None, t0), progress=progress)
    return _judged(problem, initial, run, grid, t0, name=getattr(spectrum, "name", ""),
                   source=f"{getattr(spectrum, 'source', '')}; pixels: {np.atleast_2d(t).shape[0]} of a scene",
                   solver="polish", seed=0, objective=objective_label("pixels", spp))


@float64
def starting_table(spectrum, *, grid: np.ndarray | str = "auto", reflectances=None) -> Table:
    """The table :func:`optimize_spectrum` starts from for ``spectrum``: the equal-mass
    partition of I (x + y + z) (:func:`wavelength_pdf.init.equal_mass_partition`) on the grid
    the optimizer would choose ("auto") or on ``grid``."""
    grid, problem = _grid_and_problem(spectrum, grid, reflectances)
    return Table(grid=grid.copy(), pdfs=init_mod.equal_mass_partition(problem),
                 comments=["method: start", f"name: {getattr(spectrum, 'name', '')}",
                           f"source: {_source(spectrum, reflectances)}",
                           "the optimizer's starting point: equal-mass partition of I (x + y + z) "
                           "on its grid (wavelength_pdf.init)"])


def _source(spectrum, reflectances) -> str:
    """The record's ``source``: the spectrum's, and the surface colours J was taken over."""
    from wavelength_pdf.reflectances import colours_label

    src = getattr(spectrum, "source", "")
    if reflectances is None:
        return src
    return f"{src}; reflectances: {colours_label(reflectances)}"


@float64
def evaluate_table(spectrum: Spectrum, table: Table, reflectances: ReflectanceSet | None = None,
                   objective: str = "J", objective_spp: int = DEFAULT_OBJECTIVE_SPP) -> Result:
    """Score any table (e.g. a reference table) for ``spectrum`` with the project's
    evaluator: the same record as :func:`optimize_spectrum`, judged by the same rule
    against the equal-mass initialization on the table's grid (``solver`` is ''); with
    ``reflectances``, over those surface colours (design §4.5); by ``objective`` (§4.6)."""
    check_objective(objective, objective_spp)
    t0 = time.monotonic()
    enable_compilation_cache()
    grid = np.asarray(table.grid, dtype=np.float64)
    problem = with_objective(make_problem(spectrum, grid, reflectances), objective, objective_spp)
    P = normalize_density(grid, table.pdfs)
    P0 = init_mod.equal_mass_partition(problem)
    J, J_fine = objective_mod.J_pair(problem, P)
    result = Result.judge(
        Table(grid=grid.copy(), pdfs=P), J=J, J_fine=J_fine, J_uniform=uniform.uniform_J(problem),
        J_init=objective_mod.J(problem, P0), health=health_mod.health(problem, P),
        health_init=health_mod.health(problem, P0), name=getattr(spectrum, "name", ""),
        source=_source(spectrum, reflectances), objective=objective_label(objective, objective_spp))
    result.seconds = time.monotonic() - t0
    return result
