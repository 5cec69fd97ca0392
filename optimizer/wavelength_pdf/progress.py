"""Progress of an optimization against its evaluation budget, on stderr.

On a terminal: a tqdm bar (evaluations done of the budget, rate, time left, best J). Elsewhere
(a log file, CI): a plain line at most every ``interval`` seconds and one at the end, instead
of carriage-return redraws.
"""
from __future__ import annotations

import math
import sys
import time
from typing import TextIO


class OptimizationProgress:
    """Callback ``progress(step, J)`` for :func:`wavelength_pdf.optimize_spectrum`.

    Parameters
    ----------
    name : str
        What is optimized (shown first).
    total : int
        The evaluation budget (:func:`wavelength_pdf.optimize.evaluation_budget`); the run
        may stop earlier.
    enabled : bool
        False: do nothing.
    stream : file, optional
        Where to write (default stderr).
    interval : float
        Seconds between plain lines when ``stream`` is not a terminal.
    """

    def __init__(self, name: str, total: int, enabled: bool = True, stream: TextIO | None = None,
                 interval: float = 10.0, position: int | None = None):
        self.name, self.total, self.enabled = name, int(total), enabled
        self.stream = stream if stream is not None else sys.stderr
        self.interval = interval
        self.best = math.inf
        self.step = 0
        self.start = time.monotonic()
        self.last_line = self.start
        self.bar = None
        isatty = getattr(self.stream, "isatty", lambda: False)()
        if enabled and isatty:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, desc=name[:30], unit="eval", file=self.stream,
                            leave=False, dynamic_ncols=True, position=position, mininterval=0.25)

    def __call__(self, step: int, J: float) -> None:
        if not self.enabled:
            return
        self.best = min(self.best, float(J))
        step = min(int(step), self.total)
        if self.bar is not None:
            self.bar.set_postfix_str(f"J={self.best:.5g}", refresh=False)
            self.bar.update(max(0, step - self.bar.n))
        self.step = max(self.step, step)
        now = time.monotonic()
        if self.bar is None and now - self.last_line >= self.interval:
            self.last_line = now
            self._line(now)

    def _line(self, now: float) -> None:
        elapsed = now - self.start
        left = ""
        if 0 < self.step < self.total:
            left = f", at most {elapsed * (self.total - self.step) / self.step:.0f} s left"
        print(f"{self.name}: {self.step}/{self.total} evaluations, best J {self.best:.5g}, "
              f"{elapsed:.0f} s{left}", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
        elif self.enabled and self.step:
            self._line(time.monotonic())


class _PlainLines:
    """A stream for tqdm that turns its carriage-return redraws into whole lines."""

    def __init__(self, stream: TextIO):
        self.stream = stream

    def write(self, text: str) -> int:
        for part in text.replace("\r", "\n").split("\n"):
            if part.strip():
                self.stream.write(part.rstrip() + "\n")
        return len(text)

    def flush(self) -> None:
        self.stream.flush()


def bar(*, file: TextIO | None = None, interval: float = 30.0, **kwargs):
    """A tqdm bar: redrawn in place on a terminal; elsewhere a plain line every ``interval``
    seconds (and at the end)."""
    from tqdm import tqdm

    stream = file if file is not None else sys.stderr
    if getattr(stream, "isatty", lambda: False)():
        return tqdm(file=stream, **kwargs)
    kwargs.pop("dynamic_ncols", None)
    return tqdm(file=_PlainLines(stream), mininterval=interval, maxinterval=max(interval, 10.0),
                ncols=100, ascii=True, **kwargs)
