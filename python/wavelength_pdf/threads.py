"""Thread counts that keep the optimizer's results independent of the machine's cores.

Two thread pools change the optimizer's floating-point results with their size (measured:
``optimize cie:FL11`` gave J 1.2683 on two cores and 1.2668 under ``taskset -c 0``; the
first objective evaluation already differs in its last bits):

- XLA's CPU client sizes its thread pool from the CPUs the process may run on, unless
  ``PJRT_NPROC`` is set (read once, when JAX creates its CPU backend); the pool's size
  changes how XLA splits its work, hence the rounding. :func:`pin_xla_threads` fixes it.
- OpenBLAS (NumPy's and SciPy's, used inside L-BFGS-B) splits its larger products by its
  thread count. :func:`single_threaded_blas` holds it at one thread around the solver.

Pinning XLA to 2 threads costs nothing measurable on one or two cores (alternating runs of
400 evaluations: 39.9 s with 2 threads and 39.5 s with 1 under ``taskset -c 0``); with one
thread the optimizer ran 2.5 times slower on two cores.
"""
from __future__ import annotations

import contextlib
import os
from typing import Iterator

#: Size of XLA's CPU thread pool when the package drives the process (``PJRT_NPROC``).
XLA_CPU_THREADS = 2


def pin_xla_threads(threads: int = XLA_CPU_THREADS) -> int | None:
    """Fix the size of XLA's CPU thread pool, unless the user set ``PJRT_NPROC``.

    Only effective before JAX creates its CPU backend (the command line calls it first
    thing). Returns the pool size in effect if known, else None (the backend was already
    created without it).
    """
    env = os.environ.get("PJRT_NPROC")
    if env is not None:
        return int(env) if env.strip().isdigit() else None
    try:
        from jax._src import xla_bridge  # only to ask whether the backend exists yet

        started = xla_bridge.backends_are_initialized()
    except (ImportError, AttributeError):
        started = False
    if started:
        return None
    os.environ["PJRT_NPROC"] = str(int(threads))
    return int(threads)


@contextlib.contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Run the block with one BLAS thread (threadpoolctl), restoring the count after."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield
