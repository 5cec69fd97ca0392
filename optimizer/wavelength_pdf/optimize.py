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

import importlib.util
import inspect
import math
import time
from typing import TYPE_CHECKING, Callable

import numpy as np

from . import aot, grids, health as health_mod, init as init_mod, objective
from .model import DEFAULT_GRID, normalize_density
from .precision import float64
from .result import Result
from .solvers import DEFAULT_SOLVER, SOLVERS, SolverResult
from .table import Table
from .threads import single_threaded_blas

if TYPE_CHECKING:  # annotations only: no import cost at run time
    from .reflectances import ReflectanceSet
    from .spectra import Spectrum

__all__ = ["Result", "optimize_spectrum", "evaluate_table", "evaluation_budget", "starting_table",
           "DEFAULT_GRID", "SOLVERS"]


def evaluation_budget(solver: str = DEFAULT_SOLVER, grid: np.ndarray | str = "auto",
                      solver_options: dict | None = None) -> int:
    """Most objective evaluations :func:`optimize_spectrum` spends (for progress bars)."""
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; choose one of: {', '.join(SOLVERS)}")
    n = (solver_options or {}).get("max_evals")
    if n is None:
        n = inspect.signature(SOLVERS[solver]).parameters["max_evals"].default
    return int(n)


#: A multistage result with J above this share of stratified uniform sampling's J gets a
#: second search that keeps ``SECOND_SEARCH_KEEP`` screened starts (the first keeps two) with
#: ``SECOND_SEARCH_BUDGET`` times the evaluations; the better accepted table of the two is the
#: result. On a few lamps the start that wins after polishing is the one screening dropped
#: (LSPDD 2694: 0.054 -> 0.020 x uniform); keeping three starts always would spread the budget
#: too thin on the others (docs/optimizer-speed.md).
SECOND_SEARCH_ABOVE = 0.05
SECOND_SEARCH_KEEP = 3
SECOND_SEARCH_BUDGET = 1.5


def _offset_progress(progress, offset: list):
    """Progress callback that keeps counting across successive solver runs."""
    if progress is None:
        return None

    def report(step: int, J: float) -> None:
        progress(offset[0] + step, J)

    return report


def _auto_grid(spectrum) -> np.ndarray:
    """The default grid, or for a line lamp the default grid refined around its lines."""
    return grids.auto_grid(objective.make_problem(spectrum, DEFAULT_GRID), DEFAULT_GRID)


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
        Extra keyword arguments for the solver (e.g. ``{"max_evals": 300}``). A multistage
        result above ``SECOND_SEARCH_ABOVE`` x J_uniform is followed by a second search with
        more starts kept and ``SECOND_SEARCH_BUDGET`` times the budget; the better accepted
        table wins.
    reflectances : wavelength_pdf.reflectances.ReflectanceSet, optional
        Surface colours (design §4.5): J is the weighted mean of every colour's J, and the
        health rules hold for every colour. The grid ("auto") is still chosen for the lamp.

    Raises
    ------
    ValueError
        Unknown solver, bad grid, or a spectrum without power in the grid range.
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; choose one of: {', '.join(SOLVERS)}")
    if solver == "ipopt" and importlib.util.find_spec("cyipopt") is None:
        raise ValueError("--solver ipopt needs cyipopt, an optional dependency (the ipopt extra): "
                         "install it with pip install cyipopt (it builds against Ipopt: Debian's "
                         "coinor-libipopt-dev liblapack-dev libblas-dev pkg-config)")
    t0 = time.monotonic()
    if max_seconds is not None and not (math.isfinite(max_seconds) and max_seconds > 0):
        raise ValueError(f"max_seconds must be a finite number of seconds > 0, got {max_seconds!r}")
    objective.enable_compilation_cache()
    auto = isinstance(grid, str)
    if auto and grid != "auto":
        raise ValueError(f"grid must be an array of wavelengths or 'auto', not {grid!r}")
    grid = _auto_grid(spectrum) if auto else np.asarray(grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid, reflectances)
    P0 = init_mod.equal_mass_partition(problem)
    # The reference figures every result reports, before the search: under a time cap
    # their compiling counts against it, and the search gets what is left.
    t_figures = time.monotonic()
    J_uniform = objective.uniform_J(problem)
    health_init = health_mod.health(problem, P0)
    J_init = objective.J(problem, P0)
    now = time.monotonic()
    left = None if max_seconds is None else t0 + max_seconds - now
    offset = [0]
    # A compilation cannot be cut short, and the search's (its objective with gradient)
    # takes about as long as these figures' did, cached or not: it only starts if that
    # much time is left, so a cap spent compiling is not overrun by a whole compilation.
    def search(options: dict, left: float | None) -> SolverResult:
        try:
            with single_threaded_blas(), aot.compile_deadline(None if left is None else t0 + max_seconds):
                return SOLVERS[solver](problem, P0, seed=seed, progress=_offset_progress(progress, offset),
                                       max_seconds=left, **options)
        except aot.CompileWouldOverrun as e:  # before the search had a point of its own
            return SolverResult(P=np.asarray(P0, dtype=np.float64), J=J_init,
                                message=f"{solver}: stopped by the time cap of {max_seconds:g} s ({e})")

    if left is not None and left <= now - t_figures:
        run = SolverResult(P=np.asarray(P0, dtype=np.float64), J=J_init,
                           message=f"{solver}: not started: {max(left, 0.0):.2g} s of the time "
                                   f"cap of {max_seconds:g} s were left after choosing the grid "
                                   "and compiling, less than starting the search takes")
    else:
        run = search(dict(solver_options or {}), left)
    history = list(run.history)
    offset[0] += run.nfev
    P = normalize_density(grid, run.P)
    J, J_fine = objective.J_pair(problem, P)
    health = None  # the result's, when already computed
    left = None if max_seconds is None else t0 + max_seconds - time.monotonic()
    if solver == "multistage" and J > SECOND_SEARCH_ABOVE * J_uniform and run.history and (left is None or left > 0):
        options = dict(solver_options or {})
        options["max_evals"] = int(SECOND_SEARCH_BUDGET * options.get("max_evals", evaluation_budget(solver)))
        options["n_keep"] = max(SECOND_SEARCH_KEEP, options.get("n_keep", 0))
        second = search(options, left)
        offset[0] += second.nfev
        P2 = normalize_density(grid, second.P)
        J2, J2_fine = objective.J_pair(problem, P2)
        health2 = health_mod.health(problem, P2) if J2 < J else None  # only a better table needs it
        if health2 is not None and health2.accepted(health_init):
            history += [min(history[-1], h) for h in second.history]
            run = SolverResult(P=P2, J=J2, history=history, nfev=run.nfev + second.nfev,
                               message=f"{second.message} (second search: J above {SECOND_SEARCH_ABOVE:g} x "
                                       f"uniform after the first, {J / J_uniform:.3g})")
            P, J, J_fine, health = P2, J2, J2_fine, health2
    result = Result.judge(
        Table(grid=grid.copy(), pdfs=P), J=J, J_fine=J_fine, J_uniform=J_uniform,
        J_init=J_init, health=health if health is not None else health_mod.health(problem, P),
        health_init=health_init, name=getattr(spectrum, "name", ""),
        source=_source(spectrum, reflectances), solver=solver, seed=seed, history=history,
        message=run.message)
    result.seconds = time.monotonic() - t0
    return result


@float64
def starting_table(spectrum, *, grid: np.ndarray | str = "auto", reflectances=None) -> Table:
    """The table :func:`optimize_spectrum` starts from for ``spectrum``: the equal-mass
    partition of I (x + y + z) (:func:`wavelength_pdf.init.equal_mass_partition`) on the grid
    the optimizer would choose ("auto") or on ``grid``."""
    grid = _auto_grid(spectrum) if isinstance(grid, str) else np.asarray(grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid, reflectances)
    return Table(grid=grid.copy(), pdfs=init_mod.equal_mass_partition(problem),
                 comments=["method: start", f"name: {getattr(spectrum, 'name', '')}",
                           f"source: {_source(spectrum, reflectances)}",
                           "the optimizer's starting point: equal-mass partition of I (x + y + z) "
                           "on its grid (wavelength_pdf.init)"])


def _source(spectrum, reflectances) -> str:
    """The record's ``source``: the spectrum's, and the surface colours J was taken over."""
    src = getattr(spectrum, "source", "")
    if reflectances is None:
        return src
    return f"{src}; reflectances: {reflectances.name} ({len(reflectances)} colours, {reflectances.source})"


@float64
def evaluate_table(spectrum: Spectrum, table: Table, reflectances: ReflectanceSet | None = None) -> Result:
    """Score any table (e.g. a reference table) for ``spectrum`` with the project's
    evaluator: the same record as :func:`optimize_spectrum`, judged by the same rule
    against the equal-mass initialization on the table's grid (``solver`` is ''); with
    ``reflectances``, over those surface colours (design §4.5)."""
    t0 = time.monotonic()
    objective.enable_compilation_cache()
    grid = np.asarray(table.grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid, reflectances)
    P = normalize_density(grid, table.pdfs)
    P0 = init_mod.equal_mass_partition(problem)
    J, J_fine = objective.J_pair(problem, P)
    result = Result.judge(
        Table(grid=grid.copy(), pdfs=P), J=J, J_fine=J_fine, J_uniform=objective.uniform_J(problem),
        J_init=objective.J(problem, P0), health=health_mod.health(problem, P),
        health_init=health_mod.health(problem, P0), name=getattr(spectrum, "name", ""),
        source=_source(spectrum, reflectances))
    result.seconds = time.monotonic() - t0
    return result
