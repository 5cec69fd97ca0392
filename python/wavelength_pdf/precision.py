"""Float64 for the optimizer, scoped: importing the package leaves JAX's settings alone.

The objective is optimized in float64 (float32 gradients stop L-BFGS-B early). Rather than
switching ``jax_enable_x64`` on for the whole process, the library's entry points run inside
``jax.enable_x64(True)`` (:func:`float64`), which JAX restores on the way out.
"""
from __future__ import annotations

import functools
from typing import Callable, TypeVar

import jax

F = TypeVar("F", bound=Callable)


def float64(fn: F) -> F:
    """Decorator: run ``fn`` with JAX's 64-bit types enabled (restored afterwards)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with jax.enable_x64(True):
            return fn(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
