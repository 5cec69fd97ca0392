"""The optional dependencies: which extra of the package brings which module.

Optimizing needs only the package's own dependencies (pyproject.toml); the evaluation, the
benchmark and the plots need the extras below. A command that needs one checks it before any
work starts (``require``), so a missing module is one clear line, not a traceback halfway
through a render.
"""
from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

#: Extra -> the top-level modules it installs (the same lists as pyproject.toml's extras).
EXTRAS: dict[str, tuple[str, ...]] = {
    "evaluation": ("matplotlib", "OpenEXR", "distributed"),
    "plots": ("matplotlib",),
    "mitsuba": ("mitsuba",),
    "ipopt": ("cyipopt",),
}


class MissingExtra(ValueError):
    """A command or function needs a module that an extra of the package installs."""


def _install_hint(extra: str) -> str:
    return (f"install the package with its '{extra}' extra: pip install \".[{extra}]\" in a clone, "
            f"or pip install \"WHEEL[{extra}]\"")


def missing(extra: str) -> list[str]:
    """The modules of ``extra`` that cannot be imported here (none: the extra is installed)."""
    return [name for name in EXTRAS[extra] if importlib.util.find_spec(name) is None]


def require(extra: str, what: str) -> None:
    """Raise MissingExtra naming ``what``, the absent modules and the install line, unless every
    module of ``extra`` is importable."""
    absent = missing(extra)
    if absent:
        raise MissingExtra(f"{what} needs {', '.join(absent)}, which the package does not install "
                           f"by default: {_install_hint(extra)}")


def module(name: str, extra: str) -> ModuleType:
    """Import ``name`` (a module of ``extra``), or raise MissingExtra with the install line."""
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as e:
        if e.name != name.split(".")[0]:
            raise  # the module is there but one of its own imports failed: not ours to explain
        raise MissingExtra(f"{name} is not installed: {_install_hint(extra)}") from None
