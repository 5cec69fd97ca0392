"""Optimized wavelength-sampling densities for spectral rendering under spiky lamps.

The package finds four wavelength densities whose balance-heuristic estimator of a lamp's
colour varies as little as possible in CIEDE2000 (the method of Dobos 2025, "Perception-based
Optimization of Wavelength Sampling Distributions for Spectral Rendering", TU Delft; the
contracts are in docs/design.md, §1-§4)::

    from wavelength_pdf import load_spectrum, optimize_spectrum, write_table
    result = optimize_spectrum(load_spectrum("cie:FL11"))
    if result.accepted:
        write_table("fl11.csv", result.to_table())

Importing the package leaves JAX's global settings as they were: the optimizer runs in
float64 inside its own calls.

The public API (``__all__``; typed, ``py.typed``; ``help(wavelength_pdf.NAME)`` for each):

- :func:`load_spectrum`, :func:`load_spectra` -> :class:`Spectrum` (design §3; bad input raises
  :class:`SpectrumError`, ``path:line: reason``);
- :func:`optimize_spectrum` (a :class:`Spectrum` -> :class:`Result`), :func:`evaluate_table`
  (score any :class:`Table`), :func:`evaluation_budget` (evaluations a run may spend);
- :func:`read_table`, :func:`write_table` -> :class:`Table` (design §2; :class:`TableError`).

Everything else is internal and may change between releases (CHANGELOG.md says how versions
and tags are made).
"""

from typing import TYPE_CHECKING

from wavelength_pdf._version import __version__

#: The top-level API: name -> module it lives in (imported on first use, so that
#: ``import wavelength_pdf`` and ``wavelength-pdf --help`` stay quick).
_API = {
    "optimize_spectrum": "wavelength_pdf.optimize",
    "evaluate_table": "wavelength_pdf.optimize",
    "evaluation_budget": "wavelength_pdf.optimize",
    "Result": "wavelength_pdf.result",
    "read_table": "wavelength_pdf.table",
    "write_table": "wavelength_pdf.table",
    "Table": "wavelength_pdf.table",
    "TableError": "wavelength_pdf.table",
    "load_spectrum": "wavelength_pdf.spectra",
    "load_spectra": "wavelength_pdf.spectra",
    "Spectrum": "wavelength_pdf.spectra",
    "SpectrumError": "wavelength_pdf.spectra",
}

__all__ = ["__version__", *_API]

if TYPE_CHECKING:  # what type checkers and IDEs see: the real, typed objects (tested)
    from wavelength_pdf.optimize import evaluate_table, evaluation_budget, optimize_spectrum
    from wavelength_pdf.result import Result
    from wavelength_pdf.spectra import Spectrum, SpectrumError, load_spectra, load_spectrum
    from wavelength_pdf.table import Table, TableError, read_table, write_table


def __dir__() -> list[str]:
    """The public API too (so that ``help(wavelength_pdf)`` documents every name)."""
    return sorted(set(globals()) | set(__all__))


def __getattr__(name: str) -> object:
    if name in _API:
        import importlib

        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'wavelength_pdf' has no attribute {name!r}")
