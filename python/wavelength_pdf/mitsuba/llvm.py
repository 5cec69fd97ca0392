"""Point Dr.Jit's LLVM backend at an LLVM it can use, before Mitsuba's llvm variants start.

Mitsuba 3.9's llvm variants abort with Debian 12's default LLVM 14 ("Cannot select:
fminimum") and work with LLVM 19 (Debian package ``libllvm19``). Dr.Jit reads the library's
path from the environment variable ``DRJIT_LIBLLVM_PATH`` when its LLVM backend starts, that
is, when an llvm variant is first set; so this must run before that, and it leaves a value the
user set alone.
"""
from __future__ import annotations

import os
from pathlib import Path

#: Where Debian's libllvm19 puts the library (the first one that exists is used).
CANDIDATES = (
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/aarch64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/aarch64-linux-gnu/libLLVM-19.so.1",
    "/usr/lib/llvm-19/lib/libLLVM.so.1",
    "/usr/lib/llvm-19/lib/libLLVM-19.so",
)
ENV = "DRJIT_LIBLLVM_PATH"


def ensure_llvm_path(candidates: tuple[str, ...] = CANDIDATES) -> str | None:
    """Set ``DRJIT_LIBLLVM_PATH`` to the first existing candidate unless it is already set.

    Returns
    -------
    str or None
        The value in effect afterwards (None: unset, Dr.Jit searches the system's default).
    """
    if os.environ.get(ENV):
        return os.environ[ENV]
    for c in candidates:
        if Path(c).is_file():
            os.environ[ENV] = c
            return c
    return None
