"""The one record of an optimized or evaluated table, and its comment header.

:func:`wavelength_pdf.optimize_spectrum` and :func:`wavelength_pdf.evaluate_table` return a
:class:`Result`; a written table carries it as ``key: value`` comment lines
(:meth:`Result.header_lines`), which :meth:`Result.from_table` reads back, and ``batch``'s
``summary.csv`` has one :meth:`Result.summary_row` per table. Whether a table is accepted is
decided once, by :func:`wavelength_pdf.health.rejection`, when the record is made.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from wavelength_pdf._version import __version__
from wavelength_pdf.table import Table

#: Columns of ``batch``'s summary.csv: what the run did, then the record's figures.
SUMMARY_FIELDS = [
    "input", "name", "table", "J_uniform", "J_init", "J", "J_fine", "J_over_uniform",
    "bias_rel", "std_rel_X", "std_rel_Y", "std_rel_Z", "accepted", "solver", "seconds",
    "status", "message",
]

_NAN3 = (math.nan, math.nan, math.nan)


def _num(x: Any) -> str:
    """A number at full precision (repr reads back to the same double); '' for None."""
    if x is None:
        return ""
    if isinstance(x, (np.ndarray, list, tuple)):
        return "[" + ", ".join(_num(v) for v in np.asarray(x, dtype=float).ravel()) + "]"
    return repr(float(x))


def _float(text: str | None) -> float:
    try:
        return float(text) if text not in (None, "", "None") else math.nan
    except ValueError:
        return math.nan


def _floats(text: str | None) -> np.ndarray:
    parts = [v for v in (text or "").strip("[] ").replace(",", " ").split() if v]
    vals = [_float(v) for v in parts]
    return np.array(vals if len(vals) == 3 else _NAN3, dtype=float)


def _per_channel(std) -> np.ndarray:
    """std/c per channel; with surface colours (design §4.5) the largest over the colours."""
    a = np.asarray(std, dtype=float)
    return (a if a.ndim == 1 else np.max(a, axis=0)).copy()


@dataclass
class Result:
    """An optimized (or scored) table for one spectrum and how good it is.

    Attributes
    ----------
    table : Table
        Grid (nm) and the four densities, each integrating to 1.
    name, source : str
        The spectrum's name and where it came from.
    J, J_fine : float
        J of the table at the optimizer's u-resolution and at the refined one (design §4).
    J_uniform, J_init : float
        J of stratified uniform sampling and of the equal-mass initialization.
    bias_rel : float
        Largest relative bias of the estimator's mean over X, Y, Z.
    std_rel, init_std_rel : (3,) array
        std(C(u)) / c per channel, of the table and of the initialization.
    reason : str
        Why the table is not accepted ('' if it is): :func:`health.rejection`.
    solver, message : str
        The solver used and what stopped it ('' for a scored table).
    seed : int or None
        The solver's seed.
    seconds : float
        Wall time of the call.
    history : list of float
        Best J after every objective evaluation (not written to the header).
    objective : str
        What J stands for (design §4.6): ``J`` or e.g. ``stratified, spp 64``.
    health, health_init : Health or None
        The full health reports, when computed in this process (not in the header).
    """

    table: Table
    J: float
    J_fine: float
    J_uniform: float
    J_init: float
    bias_rel: float
    std_rel: np.ndarray
    init_std_rel: np.ndarray
    reason: str = ""
    name: str = ""
    source: str = ""
    solver: str = ""
    message: str = ""
    seed: int | None = None
    seconds: float = 0.0
    history: list[float] = field(default_factory=list)
    objective: str = "J"
    health: Any = None
    health_init: Any = None

    @property
    def accepted(self) -> bool:
        """True when the acceptance rule found nothing against the table."""
        return not self.reason

    @property
    def J_over_uniform(self) -> float:
        return self.J / self.J_uniform if self.J_uniform else math.nan

    @classmethod
    def judge(cls, table: Table, *, J: float, J_fine: float, J_uniform: float, J_init: float,
              health, health_init, **rest: Any) -> "Result":
        """A record whose acceptance is decided by :func:`health.rejection`."""
        from wavelength_pdf.health import rejection

        return cls(table=table, J=float(J), J_fine=float(J_fine), J_uniform=float(J_uniform),
                   J_init=float(J_init), bias_rel=float(health.bias),
                   std_rel=_per_channel(health.std), init_std_rel=_per_channel(health_init.std),
                   reason=rejection(health, health_init, float(J), float(J_uniform)),
                   health=health, health_init=health_init, **rest)

    # --- the comment header ---------------------------------------------------------

    def header_lines(self) -> list[str]:
        """The table's comment header: a title line, then ``key: value`` lines."""
        return [
            f"wavelength-pdf {__version__}: four piecewise-linear wavelength densities, "
            "balance heuristic (design §1, §2)",
            "J = mean over u of CIEDE2000(C(u), c) (design §4), or the objective named (§4.6); J_fine: finer u quadrature; "
            "J_uniform: stratified uniform sampling; J_init: equal-mass initialization",
            f"name: {self.name}",
            f"source: {self.source}",
            f"objective: {self.objective}",
            f"J_uniform: {_num(self.J_uniform)}",
            f"J_init: {_num(self.J_init)}",
            f"J: {_num(self.J)}",
            f"J_fine: {_num(self.J_fine)}",
            f"J_over_uniform: {_num(self.J_over_uniform)}",
            f"bias_rel: {_num(self.bias_rel)}",
            f"std_rel: {_num(self.std_rel)}",
            f"init_std_rel: {_num(self.init_std_rel)}",
            f"accepted: {self.accepted}",
            f"reason: {self.reason}",
            f"solver: {self.solver}",
            f"seed: {self.seed}",
            f"seconds: {_num(self.seconds)}",
            f"message: {' '.join(self.message.split())}",
            f"version: {__version__}",
        ]

    def to_table(self) -> Table:
        """The table with this record as its comment header (ready for ``write_table``)."""
        return Table(grid=self.table.grid, pdfs=self.table.pdfs, comments=self.header_lines())

    @classmethod
    def from_table(cls, table: Table) -> "Result":
        """The record a table's header states (NaN where the header lacks a figure)."""
        h = read_header(table)
        seed = h.get("seed", "")
        reason = h.get("reason", "")
        if not reason and h.get("accepted", "True") != "True":
            reason = "not accepted when written"
        return cls(table=Table(grid=table.grid, pdfs=table.pdfs), J=_float(h.get("J")),
                   J_fine=_float(h.get("J_fine")), J_uniform=_float(h.get("J_uniform")),
                   J_init=_float(h.get("J_init")), bias_rel=_float(h.get("bias_rel")),
                   std_rel=_floats(h.get("std_rel")), init_std_rel=_floats(h.get("init_std_rel")),
                   reason=reason, name=h.get("name", ""), source=h.get("source", ""),
                   solver=h.get("solver", ""), message=h.get("message", ""),
                   seed=int(seed) if seed.lstrip("-").isdigit() else None,
                   seconds=_float(h.get("seconds")), objective=h.get("objective", "J"))

    # --- batch's summary ----------------------------------------------------------------

    def summary_row(self, input_: str, table: str, status: str, message: str = "") -> dict[str, Any]:
        """One row of ``summary.csv`` (:data:`SUMMARY_FIELDS`)."""
        std = np.asarray(self.std_rel, dtype=float)
        return {
            "input": input_, "name": self.name, "table": table,
            "J_uniform": _num(self.J_uniform), "J_init": _num(self.J_init), "J": _num(self.J),
            "J_fine": _num(self.J_fine), "J_over_uniform": _num(self.J_over_uniform),
            "bias_rel": _num(self.bias_rel), "std_rel_X": _num(std[0]),
            "std_rel_Y": _num(std[1]), "std_rel_Z": _num(std[2]), "accepted": self.accepted,
            "solver": self.solver, "seconds": _num(self.seconds), "status": status,
            "message": message,
        }


def read_header(table: Table) -> dict[str, str]:
    """The ``key: value`` comment lines of a table (the first of a repeated key wins)."""
    out: dict[str, str] = {}
    for c in table.comments:
        key, sep, value = c.partition(":")
        if sep and re.fullmatch(r"[A-Za-z_]\w*", key.strip()):
            out.setdefault(key.strip(), value.strip())
    return out
