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
import time
from typing import Callable

import numpy as np

from . import grids, health as health_mod, init as init_mod, objective, solvers
from .model import DEFAULT_GRID, trapezoid
from .precision import float64
from .result import Result
from .solvers import DEFAULT_SOLVER, SOLVERS
from .table import Table
from .threads import single_threaded_blas

#: ``grid="auto"``: refine the grid further while J is above this share of stratified
#: uniform J (the target of design §4 is 0.1).
AUTO_TARGET = 0.08

#: Evaluation budget of the polish after a further refinement.
POLISH_EVALS = 600

__all__ = ["Result", "optimize_spectrum", "evaluate_table", "evaluation_budget", "DEFAULT_GRID",
           "SOLVERS"]


def _normalize_rows(grid: np.ndarray, P: np.ndarray) -> np.ndarray:
    P = np.asarray(P, dtype=np.float64)
    return P / trapezoid(grid, P)[:, None]


def evaluation_budget(solver: str = DEFAULT_SOLVER, grid: np.ndarray | str = "auto",
                      solver_options: dict | None = None) -> int:
    """Most objective evaluations :func:`optimize_spectrum` spends (for progress bars)."""
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; choose one of: {', '.join(SOLVERS)}")
    n = (solver_options or {}).get("max_evals")
    if n is None:
        n = inspect.signature(SOLVERS[solver]).parameters["max_evals"].default
    if isinstance(grid, str):
        n += POLISH_EVALS * (len(grids.REFINED) - 1)
    return int(n)


def _offset_progress(progress, offset: list):
    """Progress callback that keeps counting across successive solver runs."""
    if progress is None:
        return None

    def report(step: int, J: float) -> None:
        progress(offset[0] + step, J)

    return report


def _auto_grid(spectrum) -> np.ndarray:
    """The default grid, or for a line lamp the default grid refined around its lines."""
    base = objective.make_problem(spectrum, DEFAULT_GRID)
    if not grids.is_spiky(base, DEFAULT_GRID):
        return DEFAULT_GRID.copy()
    n, step = grids.REFINED[0]
    return grids.refine(base, DEFAULT_GRID, n, step)


@float64
def optimize_spectrum(
    spectrum,
    *,
    grid: np.ndarray | str = "auto",
    solver: str = DEFAULT_SOLVER,
    seed: int = 0,
    progress: Callable[[int, float], None] | None = None,
    max_seconds: float | None = None,
    solver_options: dict | None = None,
) -> Result:
    """Find four wavelength densities on ``grid`` that minimize J for ``spectrum``.

    Parameters
    ----------
    spectrum : wavelength_pdf.spectra.Spectrum
        The lamp, at its own resolution.
    grid : (M+1,) array (nm), or "auto"
        Table nodes (nm), or "auto" (the default, as on the command line): the default
        grid (380..780 nm in 5 nm steps) for smooth spectra; for line lamps
        (``grids.is_spiky``) the default grid refined around the lines, and refined once
        more (then polished) if J is still above ``AUTO_TARGET`` times uniform J.
    solver : str
        A name in ``solvers.SOLVERS``.
    seed : int
        Seed of the random starting points (same input and seed, same table).
    progress : callable(step, J), optional
        Called after every objective evaluation with the best J so far.
    max_seconds : float, optional
        Wall-time cap for the solver. The solvers normally stop on an evaluation budget,
        which keeps results reproducible; a time cap that bites makes them depend on the
        machine's speed.
    solver_options : dict, optional
        Extra keyword arguments for the solver (e.g. ``{"max_evals": 300}``).

    Raises
    ------
    ValueError
        Unknown solver, bad grid, or a spectrum without power in the grid range.
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; choose one of: {', '.join(SOLVERS)}")
    if solver == "ipopt" and importlib.util.find_spec("cyipopt") is None:
        raise ValueError("--solver ipopt needs cyipopt, an optional dependency: install it with "
                         "pip install 'wavelength-pdf[ipopt]' (it builds against Ipopt, e.g. "
                         "Debian's coinor-libipopt-dev)")
    t0 = time.monotonic()
    objective.enable_compilation_cache()
    auto = isinstance(grid, str)
    if auto and grid != "auto":
        raise ValueError(f"grid must be an array of wavelengths or 'auto', not {grid!r}")
    grid = _auto_grid(spectrum) if auto else np.asarray(grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid)
    P0 = init_mod.equal_mass_partition(problem)
    offset = [0]
    with single_threaded_blas():
        run = SOLVERS[solver](problem, P0, seed=seed, progress=_offset_progress(progress, offset),
                              max_seconds=max_seconds, **(solver_options or {}))
    history = list(run.history)
    offset[0] += run.nfev
    level = 1
    while auto and level < len(grids.REFINED) and \
            objective.J(problem, run.P) > AUTO_TARGET * objective.uniform_J(problem):
        # Still above target: refine around the lines again and continue from the result.
        n, step = grids.REFINED[level]
        finer = grids.refine(problem, grid, n, step)
        if finer.size == grid.size:
            break
        fine_problem = objective.make_problem(spectrum, finer)
        P_start = np.stack([np.interp(finer, grid, p) for p in run.P])
        remaining = None if max_seconds is None else max(max_seconds - (time.monotonic() - t0), 1.0)
        fine_P0 = init_mod.equal_mass_partition(fine_problem)
        with single_threaded_blas():
            fine_run = solvers.polish(fine_problem, P_start, fine_P0,
                                      progress=_offset_progress(progress, offset),
                                      max_seconds=remaining, max_evals=POLISH_EVALS)
        offset[0] += fine_run.nfev
        history += fine_run.history
        grid, problem, P0, run = finer, fine_problem, fine_P0, fine_run
        level += 1
    P = _normalize_rows(grid, run.P)
    J, J_fine = objective.J_pair(problem, P)
    result = Result.judge(
        Table(grid=grid.copy(), pdfs=P), J=J, J_fine=J_fine, J_uniform=objective.uniform_J(problem),
        J_init=objective.J(problem, P0), health=health_mod.health(problem, P),
        health_init=health_mod.health(problem, P0), name=getattr(spectrum, "name", ""),
        source=getattr(spectrum, "source", ""), solver=solver, seed=seed, history=history,
        message=run.message)
    result.seconds = time.monotonic() - t0
    return result


@float64
def evaluate_table(spectrum, table: Table) -> Result:
    """Score any table (e.g. a reference table) for ``spectrum`` with the project's
    evaluator: the same record as :func:`optimize_spectrum`, judged by the same rule
    against the equal-mass initialization on the table's grid (``solver`` is '')."""
    t0 = time.monotonic()
    objective.enable_compilation_cache()
    grid = np.asarray(table.grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid)
    P = _normalize_rows(grid, table.pdfs)
    P0 = init_mod.equal_mass_partition(problem)
    J, J_fine = objective.J_pair(problem, P)
    result = Result.judge(
        Table(grid=grid.copy(), pdfs=P), J=J, J_fine=J_fine, J_uniform=objective.uniform_J(problem),
        J_init=objective.J(problem, P0), health=health_mod.health(problem, P),
        health_init=health_mod.health(problem, P0), name=getattr(spectrum, "name", ""),
        source=getattr(spectrum, "source", ""))
    result.seconds = time.monotonic() - t0
    return result
