"""Progress of an optimization against its evaluation budget, on stderr.

On a terminal: a tqdm bar (evaluations done of the budget, rate, time left, best J). Elsewhere
(a log file, CI): a plain line at most every ``interval`` seconds and one at the end, instead
of carriage-return redraws.

Before the first evaluation the optimizer compiles (or loads from the compile cache) its
objective: the line says so (``preparing``, e.g. :func:`preparing_message`) and shows no
estimate of the time left, which is computed from the evaluations alone once they run (a
first run's compilation, 30-60 s, would otherwise read as hours left).
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
    preparing : str, optional
        What happens before the first evaluation (default: compiling or loading the
        objective, :func:`preparing_message`), shown until it runs; '' shows nothing.
    """

    #: tqdm's layout before the first evaluation: what is going on and the time spent, no rate
    #: and no estimate of the time left.
    PREPARING_FORMAT = "{desc}: {elapsed}{postfix}"

    def __init__(self, name: str, total: int, enabled: bool = True, stream: TextIO | None = None,
                 interval: float = 10.0, position: int | None = None, preparing: str | None = None):
        self.name, self.total, self.enabled = name, int(total), enabled
        self.stream = stream if stream is not None else sys.stderr
        self.interval = interval
        self.best = math.inf
        self.step = 0
        self.start = time.monotonic()
        self.last_line = self.start
        #: (time, step) of the first evaluation seen: the estimate of the time left counts
        #: from here, not from the start (which includes compiling).
        self.first: tuple[float, int] | None = None
        self.bar = None
        if preparing is None:
            preparing = preparing_message() if enabled else ""
        self.preparing = preparing
        isatty = getattr(self.stream, "isatty", lambda: False)()
        if enabled and isatty:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, desc=name[:30], unit="eval", file=self.stream,
                            leave=False, dynamic_ncols=True, position=position, mininterval=0.25,
                            bar_format=self.PREPARING_FORMAT if preparing else None,
                            postfix=preparing or None)
        elif enabled and preparing:
            print(f"{self.name}: {preparing}", file=self.stream, flush=True)

    def __call__(self, step: int, J: float) -> None:
        if not self.enabled:
            return
        self.best = min(self.best, float(J))
        step = min(int(step), self.total)
        now = time.monotonic()
        if self.first is None:
            self.first = (now, step)
            if self.bar is not None:  # evaluations run: the normal bar, its clock from now
                self.bar.bar_format = None
                self.bar.reset(total=self.total)
        if self.bar is not None:
            self.bar.set_postfix_str(f"J={self.best:.5g}", refresh=False)
            self.bar.update(max(0, step - self.bar.n))
        self.step = max(self.step, step)
        if self.bar is None and now - self.last_line >= self.interval:
            self.last_line = now
            self._line(now)

    def time_left(self, now: float) -> float | None:
        """Seconds left at the rate of the evaluations so far (None before two are seen)."""
        if self.first is None or not (self.first[1] < self.step < self.total):
            return None
        t0, s0 = self.first
        return (now - t0) * (self.total - self.step) / (self.step - s0)

    def _line(self, now: float) -> None:
        elapsed = now - self.start
        left = ""
        seconds = self.time_left(now)
        if seconds is not None:
            left = f", at most {seconds:.0f} s left"
        print(f"{self.name}: {self.step}/{self.total} evaluations, best J {self.best:.5g}, "
              f"{elapsed:.0f} s{left}", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
        elif self.enabled and self.step:
            self._line(time.monotonic())


def preparing_message() -> str:
    """What the optimizer does before its first evaluation, from the compile cache's state:
    compiling once (a cold cache, or none) or loading compiled code (design §7)."""
    from wavelength_pdf import compile_cache

    folder = compile_cache.cache_dir()
    if folder is None:
        return (f"compiling the optimizer (usually {compile_cache.FIRST_COMPILE}; no compile "
                f"cache: ${compile_cache.ENV} is off)")
    if not compile_cache.is_warm(folder):
        return (f"compiling the optimizer once (usually {compile_cache.FIRST_COMPILE}; kept in "
                f"{folder} for later runs)")
    return (f"loading the compiled optimizer from {folder} (a grid of a new size compiles "
            f"once, {compile_cache.FIRST_COMPILE})")


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
