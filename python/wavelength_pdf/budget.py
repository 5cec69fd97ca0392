"""What one optimization may spend: objective evaluations and, optionally, wall time.

A :class:`Budget` is made once, by :func:`wavelength_pdf.optimize.optimize_spectrum` when its
call starts, and handed to the solver and, through it, to every compilation the search may
start (``aot.DiskJit``): the time cap is then one deadline read in every place that keeps it,
not a value each module recomputes from what was left when it was called.

The evaluation count is what normally stops a solver (results are reproducible); a deadline
that bites makes them depend on the machine's speed.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass


@dataclass(frozen=True)
class Budget:
    """At most ``max_evaluations`` objective evaluations, and no work past ``deadline``.

    Attributes
    ----------
    max_evaluations : int
        Value-and-gradient evaluations the solver may spend.
    deadline : float or None
        A ``time.monotonic()`` value; None: no time cap.
    seconds : float or None
        The cap as the user gave it (for messages); None with no cap.
    """

    max_evaluations: int
    deadline: float | None = None
    seconds: float | None = None

    @classmethod
    def starting(cls, max_evaluations: int, max_seconds: float | None, start: float | None = None) -> Budget:
        """``max_evaluations``, and ``max_seconds`` counted from ``start`` (a
        ``time.monotonic()`` value; default now)."""
        if max_seconds is None:
            return cls(int(max_evaluations))
        t0 = time.monotonic() if start is None else start
        return cls(int(max_evaluations), t0 + max_seconds, max_seconds)

    def seconds_left(self) -> float | None:
        """Seconds until the deadline (negative once past it); None without one."""
        return None if self.deadline is None else self.deadline - time.monotonic()

    def expired(self) -> bool:
        """Whether the deadline has passed."""
        return self.deadline is not None and time.monotonic() > self.deadline

    def with_evaluations(self, max_evaluations: int) -> Budget:
        """The same deadline with another evaluation count."""
        return dataclasses.replace(self, max_evaluations=int(max_evaluations))
