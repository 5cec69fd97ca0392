"""Public entry point: optimize the four wavelength densities for one spectrum.

    result = optimize_spectrum(load_spectrum("cie:FL11"))
    write_table("fl11.csv", result.table)        # only if result.accepted

The result carries J of the optimized table at two u-resolutions, J of stratified uniform
sampling and of the initialization (SPEC 4), and the estimator's health for the result
and for the initialization (``health.Health``); ``accepted`` is the issue's rule (bias at
most 1e-6, no channel's std worse than the initialization's).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from . import __version__, grids, health as health_mod, init as init_mod, objective, solvers
from .health import Health
from .objective import DEFAULT_GRID
from .solvers import DEFAULT_SOLVER, SOLVERS
from .table import Table

__all__ = ["Result", "optimize_spectrum", "evaluate_table", "DEFAULT_GRID", "SOLVERS"]


@dataclass
class Result:
    """Outcome of :func:`optimize_spectrum`.

    Attributes
    ----------
    table : Table
        The optimized table (grid, (4, M+1) densities normalized, header comments).
    J, J_fine : float
        J of the table at the optimizer's u-resolution and at the refined one.
    J_uniform, J_init : float
        J of stratified uniform sampling and of the equal-mass initialization.
    health, health_init : Health
        Estimator health of the table and of the initialization.
    solver : str
        Name of the solver used.
    seconds : float
        Wall time of the whole call.
    history : list of float
        Best J after every objective evaluation.
    accepted : bool
        True if the table passes the health checks against the initialization.
    message : str
        The solver's message, or why the table is not accepted.
    """

    table: Table
    J: float
    J_fine: float
    J_uniform: float
    J_init: float
    health: Health
    health_init: Health
    solver: str
    seconds: float
    history: list[float] = field(default_factory=list)
    accepted: bool = False
    message: str = ""


def _normalize_rows(grid: np.ndarray, P: np.ndarray) -> np.ndarray:
    P = np.asarray(P, dtype=np.float64)
    tot = np.sum(0.5 * (P[:, 1:] + P[:, :-1]) * np.diff(grid)[None, :], axis=1)
    return P / tot[:, None]


def _comments(spectrum, r: "Result") -> list[str]:
    h, h0 = r.health, r.health_init
    return [
        f"wavelength-pdf {__version__}: four wavelength densities (SPEC 1), balance heuristic",
        f"spectrum: {getattr(spectrum, 'name', '')}",
        f"source: {getattr(spectrum, 'source', '')}",
        f"J_uniform: {r.J_uniform!r}",
        f"J_init: {r.J_init!r}",
        f"J: {r.J!r}",
        f"J_fine: {r.J_fine!r}",
        f"bias_rel: {h.bias!r}",
        f"std_rel: {h.std[0]!r} {h.std[1]!r} {h.std[2]!r}",
        f"std_rel_init: {h0.std[0]!r} {h0.std[1]!r} {h0.std[2]!r}",
        f"accepted: {r.accepted}",
        f"solver: {r.solver}",
        f"seconds: {r.seconds:.2f}",
    ]


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


def optimize_spectrum(
    spectrum,
    *,
    grid: np.ndarray | str = DEFAULT_GRID,
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
    t0 = time.monotonic()
    objective.enable_compilation_cache()
    auto = isinstance(grid, str)
    if auto and grid != "auto":
        raise ValueError(f"grid must be an array of wavelengths or 'auto', not {grid!r}")
    grid = _auto_grid(spectrum) if auto else np.asarray(grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid)
    P0 = init_mod.equal_mass_partition(problem)
    offset = [0]
    run = SOLVERS[solver](problem, P0, seed=seed, progress=_offset_progress(progress, offset),
                          max_seconds=max_seconds, **(solver_options or {}))
    history = list(run.history)
    offset[0] += run.nfev
    P = _normalize_rows(grid, run.P)
    J, J_fine = objective.J_pair(problem, P)
    h = health_mod.health(problem, P)
    h0 = health_mod.health(problem, P0)
    accepted = h.accepted(h0)
    message = run.message if accepted else f"not accepted: {h.reason(h0)} ({run.message})"
    result = Result(
        table=Table(grid=grid.copy(), pdfs=P, comments=[]),
        J=J, J_fine=J_fine, J_uniform=objective.uniform_J(problem), J_init=objective.J(problem, P0),
        health=h, health_init=h0, solver=solver, seconds=0.0, history=history,
        accepted=accepted, message=message,
    )
    result.seconds = time.monotonic() - t0
    result.table.comments = _comments(spectrum, result)
    return result


def evaluate_table(spectrum, table: Table) -> dict:
    """Score any table (e.g. a reference table) for ``spectrum`` with the project's
    evaluator.

    Returns
    -------
    dict
        ``J``, ``J_fine``, ``J_uniform``, ``J_init``, ``health``, ``health_init`` and
        ``accepted`` (health judged against the equal-mass initialization on the
        table's grid).
    """
    objective.enable_compilation_cache()
    grid = np.asarray(table.grid, dtype=np.float64)
    problem = objective.make_problem(spectrum, grid)
    P = _normalize_rows(grid, table.pdfs)
    P0 = init_mod.equal_mass_partition(problem)
    J, J_fine = objective.J_pair(problem, P)
    h = health_mod.health(problem, P)
    h0 = health_mod.health(problem, P0)
    return {
        "J": J, "J_fine": J_fine, "J_uniform": objective.uniform_J(problem),
        "J_init": objective.J(problem, P0), "health": h, "health_init": h0,
        "accepted": h.accepted(h0),
    }
