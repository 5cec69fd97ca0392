"""Solvers that minimize J over the four densities, chosen by name from ``SOLVERS``.

Every solver is called the same way, ``SOLVERS[name](start, budget, seed=..., progress=...,
**options)``: ``start`` (:class:`Start`) is the problem with its initialization and the
figures the optimizer computed for it once (its J and health, stratified uniform sampling's
J), ``budget`` (:class:`~wavelength_pdf.budget.Budget`) what the run may spend. What a solver
needs beyond that (an optional package) its registry entry (:class:`Solver`) says.

Every solver minimizes the same function of a parameter vector x:

    J(P(x)) + mu * sum_c max(0, var_c(P(x)) / var_c(P_init) - (1 - margin))^2

- P(x) is a *parameterization* (``PARAMETERIZATIONS``) of the four densities:
  ``values`` (node values >= 0, as L-BFGS-B bounds) or ``logits`` (node values exp(x),
  free, i.e. a softmax per density). Both mix a fixed share ``DEFENSIVE`` of the support
  density s (the equal-mass mixture, positive at both ends of every segment where
  f > 0) into every density: P_k = (1 - eps) v_k / |v_k| + eps s. The mixture therefore
  never reaches zero where f > 0 (no bias), whatever the solver does; off the support the
  densities may be exactly zero.
- The penalty keeps every channel's variance of C(u) below the initialization's. J alone
  is blind to rare huge values of C(u) (fireflies) and happily trades them for a lower J;
  the health check (``health.Health.accepted``) rejects such tables, so the solvers avoid
  them in the first place.

  On a coarse level of ``multistage`` the reference is the initialization on that
  level's grid (a coarse grid cannot follow emission lines).
- The search runs on ``problem.simplify(problem, SEARCH_TOL)``; tables are judged on
  the exact problem.

The value and its gradient with respect to the parameters come from one executable per
parameterization and problem size class (``_penalized_in``: the parameterization, the
coarse level's interpolation to the table grid (``Level``: every k-th table node), the
objective and the gradient pulled back, in one call and one transfer per evaluation); every
level's parameters are padded to the table grid's count, so the levels share it.
SciPy and Ipopt see float64 NumPy arrays.

Solvers are deterministic for the same input and seed, as long as the budget's deadline does
not cut a run short (the evaluation count is what normally stops them). The deadline covers
the compiling of the solver's objective too: the clock is read before every evaluation and
before every stage (a stage that cannot start is skipped, not compiled), and no compilation
starts that would end past it (``aot``), so a run ends at most one evaluation after the cap.
"""

from __future__ import annotations

import dataclasses
import importlib.util
from dataclasses import dataclass, field
from functools import partial
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

from . import aot
from . import health as health_mod
from . import init as init_mod
from . import objective, quadrature, uniform
from . import problem as problem_mod
from .budget import Budget
from .model import normalize_density
from .problem import Problem
from .sampling import N_DENSITIES

#: Share of the support density mixed into every density (keeps the mixture positive
#: where f > 0). 1e-3 already raises J measurably on smooth lamps; 1e-6 does not.
DEFENSIVE = 1e-6

#: The variance penalty aims this far below the initialization's variance, so that the
#: accepted table (judged on the exact problem) keeps a margin.
PENALTY_MARGIN = 0.05

#: Default weight of the variance penalty, relative to J of the initialization.
PENALTY_WEIGHT = 10.0

#: Solvers search on ``problem.simplify(problem, SEARCH_TOL)`` (spectrum and CMFs on
#: fewer nodes: about half the work per evaluation) and judge results on the exact
#: problem. 0 searches on the exact problem.
SEARCH_TOL = 1e-3

#: Share of the remaining evaluations the best finalist may use on the table grid (an
#: even split: the best start after screening is often not the best after polishing).
FIRST_SHARE = 0.5

Progress = Callable[[int, float], None]


@dataclass(frozen=True)
class Start:
    """The problem, the table the search starts from, and the figures of that table that the
    optimizer reports anyway (computed once, by :meth:`of`; the solvers judge against them).

    Attributes
    ----------
    problem : Problem
        The exact problem (tables are judged on it).
    P : (4, M+1) array
        The initialization (the equal-mass partition).
    health : health.Health
        Its health: no accepted table may be worse (``Health.accepted``).
    J : float
        Its J at ``quadrature.ORDER``.
    J_uniform : float
        J of stratified uniform sampling at ``quadrature.ORDER``.
    """

    problem: Problem
    P: np.ndarray
    health: health_mod.Health
    J: float
    J_uniform: float

    @classmethod
    def of(cls, problem: Problem, P: np.ndarray) -> Start:
        """The start at ``P``, its figures computed (what the optimizer reports: stratified
        uniform sampling's J first, then the table's health and J)."""
        J_uniform = uniform.uniform_J(problem)
        health = health_mod.health(problem, P)
        return cls(problem, P, health, objective.J(problem, P), J_uniform)

    def standing_for(self, problem: Problem) -> Start:
        """The same start judged on ``problem``, the same lamp standing for another objective
        (design §4.6): its J and uniform sampling's taken again, its health kept (the health
        rules do not depend on the objective)."""
        return dataclasses.replace(self, problem=problem, J=objective.J(problem, self.P),
                                   J_uniform=uniform.uniform_J(problem))


@dataclass
class SolverResult:
    """Outcome of one solver run.

    Attributes
    ----------
    P : (4, M+1) array
        The best table found, every row normalized (the table that is written).
    J : float
        J of ``P`` at the optimizer's resolution.
    history : list of float
        Best J so far after every evaluation.
    nfev : int
        Number of value-and-gradient evaluations.
    message : str
        What stopped the solver, and which stage or start won.
    health : health.Health or None
        The health of ``P`` on the exact problem when the solver already computed it.
    """

    P: np.ndarray
    J: float
    history: list[float] = field(default_factory=list)
    nfev: int = 0
    message: str = ""
    health: health_mod.Health | None = None


def _written(problem: Problem, P: np.ndarray) -> np.ndarray:
    """The table as it is written: every row scaled to integrate to 1 by the trapezoid rule
    (the rule ``optimize`` applies to the tables it scores, so J here is J there)."""
    return normalize_density(problem.grid, P)


def initialization_result(start: Start, message: str) -> SolverResult:
    """The result of a run that found nothing: the initialization, as it is written."""
    P = _written(start.problem, start.P)
    return SolverResult(P=P, J=objective.J(start.problem, P), message=message)


def _put(x) -> jax.Array:
    """A float64 NumPy vector on the device: a plain transfer (jnp.asarray compiles a
    staging function per shape outside a trace)."""
    return jax.device_put(np.asarray(x, dtype=np.float64))


class _OutOfBudget(Exception):
    """Raised inside an objective call when the evaluation or time budget is spent."""


# --- Parameterizations ---------------------------------------------------------------


def _mix(v, s, dg):
    """(1 - eps) v / |v| + eps s, |v| by the trapezoid rule; v = 0 gives s."""
    total = jnp.sum(0.5 * (v[:, 1:] + v[:, :-1]) * dg[None, :], axis=1)
    pos = total > 0
    vn = jnp.where(pos[:, None], v / jnp.where(pos, total, 1.0)[:, None], s[None, :])
    return (1.0 - DEFENSIVE) * vn + DEFENSIVE * s[None, :]


def _values_to_P(x, E, s, mask, dg):
    v = x.reshape(N_DENSITIES, -1) * mask[None, :]
    return _mix(v @ E.T, s, dg)


def _logits_to_P(x, E, s, mask, dg):
    th = x.reshape(N_DENSITIES, -1)
    th = jnp.where(mask[None, :], th, -jnp.inf)
    v = jnp.exp(th - jnp.max(th, axis=1, keepdims=True))
    return _mix(v @ E.T, s, dg)


def _values_from_V(V, mask):
    return (np.maximum(V, 0.0) * mask[None, :]).ravel()


def _logits_from_V(V, mask, floor=1e-9):
    v = np.maximum(V, 0.0)
    v = np.maximum(v, floor * np.max(v, axis=1, keepdims=True))
    return np.where(mask[None, :], np.log(v), 0.0).ravel()


@dataclass(frozen=True)
class Parameterization:
    """A map from a flat parameter vector to a table, its inverse, and whether it is
    bounded (v >= 0) or free.

    ``to_P(x, E, s, mask, dg)``: node values v on a level grid (from x), interpolated to
    the table grid by E, normalized and mixed with the support density s.
    ``from_V(V, mask)``: parameters whose node values are V (rows of any scale).
    """

    name: str
    to_P: Callable
    from_V: Callable
    bounded: bool


PARAMETERIZATIONS = {
    "values": Parameterization("values", _values_to_P, _values_from_V, True),
    "logits": Parameterization("logits", _logits_to_P, _logits_from_V, False),
}


@partial(aot.disk_jit, static_argnames=("name",))
def _to_P(x, E, s, mask, dg, name):
    return PARAMETERIZATIONS[name].to_P(x, E, s, mask, dg)


@partial(aot.disk_jit, static_argnames=("name",))
def _to_V(x, E, s, mask, dg, name):
    """Node values on the level grid (normalization aside) of parameters x."""
    if name == "values":
        return x.reshape(N_DENSITIES, -1) * mask[None, :]
    th = jnp.where(mask[None, :], x.reshape(N_DENSITIES, -1), -jnp.inf)
    return jnp.exp(th - jnp.max(th, axis=1, keepdims=True))


@partial(aot.disk_jit, static_argnames=("name",))
def _penalized_in(x, E, s, mask, dg, arr, glx, glw, var_ref, mu, margin, name):
    """[value, J, E[C]..., E[(C - c)^2]..., gradient...] of the penalized objective (``objective.penalized``) at
    parameters x of parameterization ``name``: one executable and one transfer per
    evaluation (the map to the table, the objective and its gradient pulled back to x,
    which as three calls cost a third more time)."""
    def value(y):
        P = PARAMETERIZATIONS[name].to_P(y, E, s, mask, dg)
        return objective.penalized(P, arr, glx, glw, var_ref, mu, margin)

    (val, (J, m1, m2)), g = jax.value_and_grad(value, has_aux=True)(x)
    return jnp.concatenate([jnp.stack([val, J]), m1.ravel(), m2.ravel(), g])


# --- Levels: coarser grids embedded in the table grid ---------------------------------


@dataclass(frozen=True)
class Level:
    """A grid made of every ``stride``-th table node (and the last one).

    A piecewise-linear function on it is also one on the table grid (E interpolates it
    exactly), so a coarse level is just a parameterization of fewer unknowns: it shares
    the compiled objective, smooths the landscape and converges in fewer iterations.
    """

    stride: int
    grid: np.ndarray
    E: np.ndarray  # (M+1, L) interpolation from level nodes to table nodes
    mask: np.ndarray  # (L,) level nodes whose hat meets the support


def make_level(table_grid: np.ndarray, support: np.ndarray, stride: int) -> Level:
    idx = np.arange(0, table_grid.size, stride)
    if idx[-1] != table_grid.size - 1:
        idx = np.append(idx, table_grid.size - 1)
    g = table_grid[idx]
    E = np.zeros((table_grid.size, g.size))
    for j in range(g.size):
        e = np.zeros(g.size)
        e[j] = 1.0
        E[:, j] = np.interp(table_grid, g, e)
    mask = (E.T @ support.astype(float)) > 0
    return Level(stride=stride, grid=g, E=E, mask=mask)


# --- Shared state of one optimization ------------------------------------------------


class _Context:
    """Problem data, the penalty reference, the budget and the best point seen."""

    def __init__(self, start: Start, budget: Budget, progress: Progress | None,
                 penalty_weight: float = PENALTY_WEIGHT, search_tol: float | None = None,
                 search_order: int | None = None):
        problem, P_init = start.problem, start.P
        self.budget = budget
        self.timed_out = False
        self.problem = problem
        self.search = problem_mod.simplify(problem, SEARCH_TOL if search_tol is None else search_tol)
        self.arr = self.search.arrays
        self.order = quadrature.SEARCH_ORDER if search_order is None else search_order
        self.glx, self.glw = quadrature.gauss_legendre(self.order)
        s = init_mod.support_density(problem)
        self.s = jax.device_put(s)
        self.support = s > 0
        self.dg = jax.device_put(np.diff(problem.grid))
        self.health_init = start.health
        self.fine = make_level(problem.grid, self.support, 1)
        self._jlevels: dict[int, tuple] = {}
        self._padded: dict[int, tuple] = {}
        self._exes: dict[str, Callable] = {}
        self._unit = jax.device_put(np.ones_like(self.search.c))
        # The penalty compares variances on the search problem, the acceptance on the
        # exact one (``health_init``).
        self.J_init, self.var_ref = self._reference(self.fine, P_init)
        self._var_refs: dict[int, jax.Array] = {1: self.var_ref}
        # The ``pixels`` objective is itself a variance over every pixel's colour, and its
        # health rule is the white surface's (``health.health``): a penalty per basis colour
        # and channel (some nearly black) would hold it to what the image does not show.
        self.mu = 0.0 if problem.objective == "pixels" else float(penalty_weight * max(self.J_init, 1e-3))
        self.progress = progress
        # A count of its own: a repair run (``_best_accepted``) extends it.
        self.max_evals = budget.max_evaluations
        self.nfev = 0
        self.history: list[float] = []
        self.best_J = np.inf

    def _reference(self, level: Level, V: np.ndarray) -> tuple[float, jax.Array]:
        """J and the per-channel variance of C(u) (floored above 0) of the table with node
        values V on ``level``, on the search problem."""
        x = PARAMETERIZATIONS["values"].from_V(V, level.mask)
        _, J, m1, m2, _ = self.evaluate(x, level, "values", self._unit, 0.0)
        c = self.search.c
        return J, jax.device_put(np.maximum(self.variance(m1, m2), 1e-24 * c**2 + 1e-300))

    def variance(self, m1: np.ndarray, m2: np.ndarray) -> np.ndarray:
        """Per-channel variance of C(u) from E[C] and E[(C - c)^2] (search problem)."""
        return np.maximum(m2 - (m1 - self.search.c) ** 2, 0.0)

    def evaluate(self, x: np.ndarray, level: Level, name: str, var_ref: jax.Array, mu: float):
        """(penalized value, J, E[C], E[(C - c)^2], gradient) at parameters x of ``name`` on
        ``level``, on the search problem.

        Every level's parameters are padded with masked-out zeros to the table grid's
        count, so that all levels share one executable per parameterization: loading one
        from the disk cache takes 0.1-0.3 s, as long as hundreds of evaluations."""
        n, full = level.E.shape[1], self.fine.E.shape[1]
        if level.stride not in self._padded:
            E = np.zeros((level.E.shape[0], full))
            E[:, :n] = level.E
            mask = np.concatenate([level.mask, np.zeros(full - n, dtype=bool)])
            self._padded[level.stride] = (jax.device_put(E), jax.device_put(mask))
        E, mask = self._padded[level.stride]
        xp = np.zeros((N_DENSITIES, full))
        xp[:, :n] = np.reshape(x, (N_DENSITIES, n))
        args = (_put(xp.ravel()), E, self.s, mask, self.dg, self.arr, self.glx, self.glw, var_ref, mu,
                PENALTY_MARGIN)
        exe = self._exes.get(name)
        if exe is None:
            exe = self._exes[name] = _penalized_in.bind(*args, name=name, budget=self.budget)
        out = np.asarray(exe(*args), dtype=np.float64)
        k = self.search.c.size
        m1 = out[2:2 + k].reshape(self.search.c.shape)
        m2 = out[2 + k:2 + 2 * k].reshape(self.search.c.shape)
        g = out[2 + 2 * k:].reshape(N_DENSITIES, full)[:, :n].ravel()
        return float(out[0]), float(out[1]), m1, m2, g

    def level(self, stride: int) -> Level:
        return self.fine if stride == 1 else make_level(self.problem.grid, self.support, stride)

    def var_ref_for(self, level: Level) -> jax.Array:
        """The variance a level is held to: the initialization's on that level's grid (a
        coarse grid cannot follow lines, so the table grid's would be out of reach)."""
        if level.stride not in self._var_refs:
            V = init_mod.equal_mass_partition(self.problem, level.grid)
            self._var_refs[level.stride] = self._reference(level, V)[1]
        return self._var_refs[level.stride]

    def _j(self, level: Level):
        key = level.stride
        if key not in self._jlevels:
            self._jlevels[key] = (jax.device_put(level.E), jax.device_put(level.mask))
        return self._jlevels[key]

    def out_of_budget(self) -> bool:
        if self.nfev >= self.max_evals:
            return True
        if self.budget.expired():
            self.timed_out = True
        return self.timed_out

    def table(self, x: np.ndarray, level: Level, name: str) -> np.ndarray:
        E, mask = self._j(level)
        return np.asarray(_to_P(_put(x), E, self.s, mask, self.dg, name, budget=self.budget))

    def values(self, x: np.ndarray, level: Level, name: str) -> np.ndarray:
        E, mask = self._j(level)
        return np.asarray(_to_V(_put(x), E, self.s, mask, self.dg, name, budget=self.budget))

    def bounds(self, level: Level, name: str):
        if not PARAMETERIZATIONS[name].bounded:
            return None
        ub = np.where(np.tile(level.mask, N_DENSITIES), np.inf, 0.0)
        return scipy.optimize.Bounds(np.zeros_like(ub), ub)

    def fun(self, level: Level, name: str, tracker: "_Tracker"):
        """The scalar objective with gradient for SciPy/Ipopt in parameterization ``name``
        on ``level`` (variance penalty against ``var_ref_for(level)``)."""
        var_ref = self.var_ref_for(level)

        def f(x: np.ndarray):
            if self.out_of_budget():
                raise _OutOfBudget
            try:
                val, J, _, _, g = self.evaluate(x, level, name, var_ref, self.mu)
            except aot.CompileWouldOverrun:  # the time cap: keep the best point so far
                self.timed_out = True
                raise _OutOfBudget from None
            self.nfev += 1
            if not np.isfinite(val) or not np.all(np.isfinite(g)):
                # A step into a region the objective cannot evaluate: make it unattractive.
                return 1e300, np.zeros_like(g)
            tracker.offer(x, val, J)
            self.best_J = min(self.best_J, J)
            self.history.append(self.best_J)
            if self.progress is not None:
                self.progress(self.nfev, self.best_J)
            return val, g

        return f


class _Tracker:
    """Best point of one run (by penalized value)."""

    def __init__(self):
        self.x = None
        self.val = np.inf
        self.J = np.inf

    def offer(self, x, val, J):
        if val < self.val:
            self.x, self.val, self.J = np.array(x, copy=True), val, J


@dataclass
class _Point:
    """A candidate: node values on a level grid, its penalized value and J."""

    V: np.ndarray
    level: Level
    val: float = np.inf
    J: float = np.inf
    name: str = ""

    def on(self, level: Level) -> np.ndarray:
        """Node values on another (finer) level: exact interpolation."""
        if level.stride == self.level.stride:
            return self.V
        return np.stack([np.interp(level.grid, self.level.grid, v) for v in self.V])


def _run_scipy(ctx: _Context, start: _Point, level: Level, name: str, method: str, maxiter: int) -> _Point:
    """One SciPy run from ``start`` on ``level`` in parameterization ``name``."""
    V0 = start.on(level)
    if ctx.out_of_budget():  # skipped before its level's reference is computed (compiled)
        return _Point(V=V0, level=level, val=start.val, J=start.J, name=start.name)
    x0 = PARAMETERIZATIONS[name].from_V(V0, level.mask)
    tracker = _Tracker()
    f = ctx.fun(level, name, tracker)
    try:
        if method == "L-BFGS-B":
            scipy.optimize.minimize(
                f, x0, jac=True, method="L-BFGS-B", bounds=ctx.bounds(level, name),
                options={"maxiter": maxiter, "maxfun": 2 * maxiter, "maxcor": 20, "ftol": 1e-12, "gtol": 1e-10},
            )
        else:
            scipy.optimize.minimize(
                f, x0, jac=True, method="trust-constr", bounds=ctx.bounds(level, name),
                hess=scipy.optimize.BFGS(), options={"maxiter": maxiter, "gtol": 1e-10, "xtol": 1e-12},
            )
    except _OutOfBudget:
        pass
    if tracker.x is None:
        return _Point(V=V0, level=level, val=start.val, J=start.J, name=start.name)
    return _Point(V=ctx.values(tracker.x, level, name), level=level, val=tracker.val, J=tracker.J,
                  name=start.name)


def _start(ctx: _Context, P: np.ndarray, name: str = "") -> _Point:
    return _Point(V=np.asarray(P, dtype=np.float64), level=ctx.fine, name=name)


def _table_of(ctx: _Context, pt: _Point) -> np.ndarray:
    """The table (4, M+1) of a candidate, as the solvers evaluate it."""
    x = PARAMETERIZATIONS["values"].from_V(pt.V, pt.level.mask)
    return ctx.table(x, pt.level, "values")


# --- Solvers -------------------------------------------------------------------------


def _finish(ctx: _Context, P: np.ndarray, message: str) -> SolverResult:
    if ctx.timed_out:
        message += "; stopped by the time cap"
    P = _written(ctx.problem, P)
    return SolverResult(P=P, J=objective.J(ctx.problem, P), history=list(ctx.history),
                        nfev=ctx.nfev, message=message)


def lbfgsb(start: Start, budget: Budget, *, seed: int = 0, progress: Progress | None = None,
           parameterization: str = "logits") -> SolverResult:
    """SciPy L-BFGS-B from the initialization on the table grid, in one parameterization
    (``logits``: unconstrained softmax; ``values``: bounds v >= 0)."""
    ctx = _Context(start, budget, progress)
    pt = _run_scipy(ctx, _start(ctx, start.P), ctx.fine, parameterization, "L-BFGS-B", budget.max_evaluations)
    return _finish(ctx, _table_of(ctx, pt), f"lbfgsb/{parameterization}: {ctx.nfev} evaluations")


def trust_constr(start: Start, budget: Budget, *, seed: int = 0, progress: Progress | None = None) -> SolverResult:
    """SciPy trust-constr (trust-region SQP with a BFGS Hessian) in the logits
    parameterization, which needs no bounds (its interior-point mode for the bounds of
    the values parameterization barely moves within a practical budget)."""
    ctx = _Context(start, budget, progress)
    pt = _run_scipy(ctx, _start(ctx, start.P), ctx.fine, "logits", "trust-constr", budget.max_evaluations)
    return _finish(ctx, _table_of(ctx, pt), f"trust-constr: {ctx.nfev} evaluations")


def ipopt(start: Start, budget: Budget, *, seed: int = 0, progress: Progress | None = None) -> SolverResult:
    """Ipopt (cyipopt, MUMPS linear solver, limited-memory Hessian) with bounds v >= 0.

    Searches with ``quadrature.ORDER`` points per u-piece, not the midpoint rule of the
    other solvers: Ipopt's filter line search stalls on the midpoint rule's small kinks
    (on the test lamp it made no progress in 40 evaluations)."""
    import cyipopt

    P0, max_evals = start.P, budget.max_evaluations
    ctx = _Context(start, budget, progress, search_order=quadrature.ORDER)
    level = ctx.fine
    x0 = PARAMETERIZATIONS["values"].from_V(np.asarray(P0), level.mask)
    tracker = _Tracker()
    f = ctx.fun(level, "values", tracker)
    ub = np.where(np.tile(level.mask, N_DENSITIES), 1e19, 0.0)
    message = ""
    try:
        res = cyipopt.minimize_ipopt(
            f, x0, jac=True, bounds=list(zip(np.zeros_like(ub), ub)),
            options={"max_iter": max_evals, "hessian_approximation": "limited-memory",
                     "linear_solver": "mumps", "print_level": 0, "sb": "yes", "tol": 1e-10},
        )
        message = str(res.message)
    except _OutOfBudget:
        message = "evaluation budget spent"
    P = np.asarray(P0) if tracker.x is None else ctx.table(tracker.x, level, "values")
    return _finish(ctx, P, f"ipopt: {message}")


#: A multistage result with J above this share of stratified uniform sampling's J gets a
#: second search that keeps ``SECOND_SEARCH_KEEP`` screened starts (the first keeps two) with
#: ``SECOND_SEARCH_BUDGET`` times the evaluations; the better accepted table of the two is the
#: result. On a few lamps the start that wins after polishing is the one screening dropped
#: (LSPDD 2694: 0.054 -> 0.020 x uniform); keeping three starts always would spread the budget
#: too thin on the others (docs/optimizer-speed.md).
SECOND_SEARCH_ABOVE = 0.05
SECOND_SEARCH_KEEP = 3
SECOND_SEARCH_BUDGET = 1.5


def _counting_on(progress: Progress | None, offset: int) -> Progress | None:
    """Progress callback of a later run that keeps counting after ``offset`` evaluations."""
    if progress is None:
        return None
    return lambda step, J: progress(offset + step, J)


def multistage(start: Start, budget: Budget, *, seed: int = 0, progress: Progress | None = None,
               n_keep: int = 2, **options) -> SolverResult:
    """:func:`multistage_once`; a result above ``SECOND_SEARCH_ABOVE`` x J_uniform is
    followed by a second search with at least ``SECOND_SEARCH_KEEP`` starts kept and
    ``SECOND_SEARCH_BUDGET`` times the evaluations (the same deadline), whose table replaces
    the first only if its J is lower and it is accepted."""
    first = multistage_once(start, budget, seed=seed, progress=progress, n_keep=n_keep, **options)
    if not (first.J > SECOND_SEARCH_ABOVE * start.J_uniform and first.history and not budget.expired()):
        return first
    more = budget.with_evaluations(int(SECOND_SEARCH_BUDGET * budget.max_evaluations))
    second = multistage_once(start, more, seed=seed, progress=_counting_on(progress, first.nfev),
                             n_keep=max(SECOND_SEARCH_KEEP, n_keep), **options)
    health = health_mod.health(start.problem, second.P) if second.J < first.J else None  # only a better table needs it
    if health is None or not health.accepted(start.health):
        return dataclasses.replace(first, nfev=first.nfev + second.nfev)
    history = first.history + [min(first.history[-1], h) for h in second.history]
    return SolverResult(P=second.P, J=second.J, history=history, nfev=first.nfev + second.nfev,
                        message=f"{second.message} (second search: J above {SECOND_SEARCH_ABOVE:g} x "
                                f"uniform after the first, {first.J / start.J_uniform:.3g})", health=health)


def multistage_once(start: Start, budget: Budget, *, seed: int = 0, progress: Progress | None = None,
                    strides: tuple[int, ...] = (4, 1), screen_iters: int = 60, n_random: int = 0,
                    n_keep: int = 2, coarse_iters: int = 150, stage_iters: int = 150,
                    starts: tuple[str, ...] = ("quarters", "windows"),
                    fine_starts: tuple[str, ...] = ("equal-mass",), first_share: float = FIRST_SHARE
                    ) -> SolverResult:
    """Multi-start, multi-level, multi-parameterization L-BFGS-B; keeps the best accepted.

    1. Screen on the coarsest level (every ``strides[0]``-th table node): a short run in
       the logits (softmax) parameterization from each of ``starts`` (names of
       ``init.starting_points``: the range quarters and windows, which win on smooth
       spectra; the other starts rarely win and cost evaluations) and ``n_random``
       random ones; and the same on the table grid from each of ``fine_starts`` (the
       equal-mass partition, which wins on line lamps, where a coarse grid would lose
       the lines).
    2. Carry the ``n_keep`` best through the finer levels (logits, ``coarse_iters``
       each); a coarse table is exactly representable on a finer grid.
    3. On the table grid, share the remaining budget among them: alternate runs in the
       logits and the bounded values parameterization until a round gains less than 0.1 %.
       Logits move mass smoothly and cannot reach zero; bounded values can put exact zeros
       and lift them again.
    4. Return the lowest-J table among them that the health check accepts (unbiased, no
       channel's std above the initialization's); the initialization itself if none is.
    """
    problem, P0, max_evals = start.problem, start.P, budget.max_evaluations
    ctx = _Context(start, budget, progress)
    levels = [ctx.level(k) for k in strides if k >= 1 and (k == 1 or problem.grid.size > 4 * k)]
    if not levels or levels[-1].stride != 1:
        levels.append(ctx.fine)
    coarse = levels[0]
    all_starts = init_mod.starting_points(problem, seed=seed, n_random=n_random, grid=coarse.grid)
    fine_all = init_mod.starting_points(problem, seed=seed, n_random=0)
    todo = [(k, V, coarse) for k, V in all_starts.items() if k in starts or k.startswith("random")]
    todo += [(k, fine_all[k], ctx.fine) for k in fine_starts if k in fine_all]
    # Small budgets shrink the screening and the intermediate levels so that at least
    # half of the evaluations are left for the table grid (L-BFGS-B uses ~1.2
    # evaluations per iteration).
    screen_iters = max(3, min(screen_iters, int(0.3 * max_evals / (1.2 * max(len(todo), 1)))))
    n_mid = max(len(levels) - 2, 1) * n_keep
    coarse_iters = max(3, min(coarse_iters, int(0.2 * max_evals / (1.2 * n_mid))))
    screened = []
    for name, V, level in todo:
        if ctx.out_of_budget():
            break
        pt = _run_scipy(ctx, _Point(V=V, level=level, name=name), level, "logits", "L-BFGS-B", screen_iters)
        screened.append(pt)
    screened.sort(key=lambda p: p.val)
    kept = screened[:n_keep]
    for level in levels[1:-1]:
        kept = [_run_scipy(ctx, pt, level, "logits", "L-BFGS-B", coarse_iters) for pt in kept]
        kept.sort(key=lambda p: p.val)
    fine = levels[-1]
    finalists = []
    for rank, pt in enumerate(kept):
        # The most promising candidate may use most of what is left; a stalled one
        # leaves the rest to the next.
        left = ctx.max_evals - ctx.nfev
        share = left if rank == len(kept) - 1 else int(left * first_share)
        finalists.append(_alternate(ctx, pt, fine, ctx.nfev + share, stage_iters))
    return _best_accepted(ctx, finalists, P0, "multistage")


def _alternate(ctx: _Context, pt: _Point, level: Level, stop_at: int, stage_iters: int) -> tuple[_Point, int]:
    """Alternate logits and bounded-values L-BFGS-B runs on ``level`` until a round gains
    less than 0.1 % or ``stop_at`` evaluations are reached; returns (best, rounds).

    Logits first: from a screened start they make the larger gains per evaluation."""
    rounds = 0
    while not ctx.out_of_budget() and ctx.nfev < stop_at:
        before = pt.val
        for pname in ("logits", "values"):
            if ctx.out_of_budget() or ctx.nfev >= stop_at:
                break
            new = _run_scipy(ctx, pt, level, pname, "L-BFGS-B", min(stage_iters, stop_at - ctx.nfev))
            if new.val <= pt.val:
                pt = new
        rounds += 1
        if pt.val > before * (1.0 - 1e-3):
            break
    return pt, rounds


#: When no finalist passes the health check: up to this many more runs from the best one,
#: each with a ten times heavier variance penalty and ``REPAIR_SHARE`` of the evaluation
#: budget on top of it.
REPAIRS = 2
REPAIR_SHARE = 0.15


def _best_accepted(ctx: _Context, finalists: list, P0: np.ndarray, who: str) -> SolverResult:
    """The lowest-value finalist whose table passes the health check, else P0.

    The variance penalty is soft and judged on the search problem, the health check is
    exact, so a finalist still falling steeply when the budget ends can miss the check by a
    hair (a line at the range's edge: X's std 0.5 % above the initialization's), and
    returning the initialization then throws the whole search away (0.13 x uniform instead
    of 0.02). Before that, the best finalist is run again with a heavier penalty (the same
    executable: the weight is an argument)."""
    finalists = sorted(finalists, key=lambda t: t[0].val)

    def first_accepted(cands, note=""):
        for pt, rounds in cands:
            P = _table_of(ctx, pt)
            if health_mod.health(ctx.problem, P).accepted(ctx.health_init):
                return _finish(ctx, P, f"{who}: best start '{pt.name}' after {rounds} round(s), "
                                       f"{ctx.nfev} evaluations{note}")
        return None

    found = first_accepted(finalists)
    if found is not None:
        return found
    extra = int(REPAIR_SHARE * ctx.max_evals)
    # A repair weighs the variance penalty heavier: without one (``mu`` 0, the ``pixels``
    # objective) there is nothing to weigh, and a basis colour's zero variance reference
    # would divide 0 by 0.
    repairs = REPAIRS if finalists and extra >= 10 and not ctx.timed_out and ctx.mu > 0 else 0
    pt, rounds = finalists[0] if finalists else (None, 0)
    for k in range(1, repairs + 1):
        # Hold every channel where the exact problem is worse than the search problem says
        # to a reference lowered by that discrepancy, with a heavier weight.
        x = PARAMETERIZATIONS["values"].from_V(pt.on(ctx.fine), ctx.fine.mask)
        ref_device = ctx.var_ref_for(ctx.fine)
        ref = np.asarray(ref_device)
        _, _, m1, m2, _ = ctx.evaluate(x, ctx.fine, "values", ref_device, ctx.mu)
        on_search = ctx.variance(m1, m2) / ref
        exact = (health_mod.health(ctx.problem, _table_of(ctx, pt)).std / ctx.health_init.std) ** 2
        ctx._var_refs[1] = jax.device_put(ref * np.minimum(1.0, on_search / np.maximum(exact, 1e-300)))
        ctx.mu *= 10.0
        ctx.max_evals = ctx.nfev + extra
        pt = _run_scipy(ctx, pt, ctx.fine, "values", "L-BFGS-B", extra)
        found = first_accepted([(pt, rounds)], f" (then {k} run(s) with a heavier variance penalty)")
        if found is not None:
            return found
    return _finish(ctx, np.asarray(P0), f"{who}: no optimized table passed the health check; "
                   "returning the initialization")


def polish(start: Start, P_from: np.ndarray, budget: Budget, *, progress: Progress | None = None,
           stage_iters: int = 100) -> SolverResult:
    """Continue from the table ``P_from`` on the problem's grid (e.g. a solution from a
    coarser grid, interpolated): the table-grid stage of ``multistage`` alone. ``start`` is
    the initialization the health check compares with."""
    ctx = _Context(start, budget, progress)
    pt = _Point(V=np.asarray(P_from, dtype=np.float64), level=ctx.fine, name="previous")
    return _best_accepted(ctx, [_alternate(ctx, pt, ctx.fine, budget.max_evaluations, stage_iters)],
                          start.P, "polish")


#: Evaluations :func:`refine` may spend (on top of the J search it starts from).
REFINE_EVALUATIONS = 200


def refine(start: Start, found: SolverResult, budget: Budget, *, progress: Progress | None = None) -> SolverResult:
    """Aim a J search's table at another objective (design §4.6): :func:`polish` it on
    ``start.problem`` (the same grid and initialization, standing for that objective), and
    the initialization too where that is already better than J's table by it; return the
    best of them by that objective among those the health check accepts, never worse than
    the initialization.

    Started from the equal-mass partition alone, L-BFGS-B on the ``stratified`` objective
    stops in a nearby local minimum (CIE FL11, 64 spp: 1.65, where J's table already scores
    1.08 and its polish 1.01); on other lamps J's basin is worse than the start by the new
    objective (LSPDD 2482 at 64 spp: 2.10 against 1.64)."""
    J_found = objective.J(start.problem, found.P)
    health = found.health or health_mod.health(start.problem, found.P)
    best = None
    if health.accepted(start.health):
        best = dataclasses.replace(found, J=J_found, health=health,
                                   message=f"{found.message}; the polish found nothing better")
    sources = [("J's table", found.P)] + ([("the initialization", start.P)] if start.J < J_found else [])
    nfev = found.nfev
    for k, (what, P_from) in enumerate(sources):
        # Each polish returns an accepted table (the initialization if nothing better passed);
        # its history is in the new objective's values, counted on after the J search's.
        share = budget.with_evaluations((budget.max_evaluations - (nfev - found.nfev)) // (len(sources) - k))
        run = polish(start, P_from, share, progress=_counting_on(progress, nfev))
        nfev += run.nfev
        if best is None or run.J < best.J:
            best = dataclasses.replace(run, message=f"{found.message}; then from {what}: {run.message}")
    return dataclasses.replace(best, nfev=nfev)


@dataclass(frozen=True)
class Solver:
    """A registry entry: how to run a solver, and what it needs.

    ``run(start, budget, seed=..., progress=..., **options)`` does the work;
    ``max_evaluations`` is its evaluation count when none is given; ``requires`` names an
    optional package it imports (``install`` says how to get it). Calling the entry runs
    the solver within its budget: a compilation that would end past the deadline stops it
    before it found a point of its own, and the initialization is the result.
    """

    name: str
    run: Callable[..., SolverResult]
    max_evaluations: int
    requires: str = ""
    install: str = ""

    def check_available(self) -> None:
        """Raise ValueError, saying how to install it, when a package it needs is missing."""
        if self.requires and importlib.util.find_spec(self.requires) is None:
            raise ValueError(f"--solver {self.name} needs {self.requires}, an optional dependency "
                             f"{self.install}")

    def __call__(self, start: Start, budget: Budget | None = None, **options) -> SolverResult:
        budget = Budget(self.max_evaluations) if budget is None else budget
        try:
            return self.run(start, budget, **options)
        except aot.CompileWouldOverrun as e:  # before the search had a point of its own
            return initialization_result(start, f"{self.name}: stopped by the time cap of "
                                                f"{budget.seconds:g} s ({e})")


#: Solvers by name (``--solver`` on the command line).
SOLVERS: dict[str, Solver] = {s.name: s for s in (
    Solver("multistage", multistage, 1000),
    Solver("lbfgsb", lbfgsb, 900),
    Solver("trust-constr", trust_constr, 400),
    Solver("ipopt", ipopt, 900, requires="cyipopt", install=(
        "(the ipopt extra): install it with pip install cyipopt (it builds against Ipopt: Debian's "
        "coinor-libipopt-dev liblapack-dev libblas-dev pkg-config)")),
)}

#: The solver used when none is named.
DEFAULT_SOLVER = "multistage"
