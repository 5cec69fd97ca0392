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
"""

__version__ = "0.1.0"

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


def __getattr__(name: str):
    if name in _API:
        import importlib

        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'wavelength_pdf' has no attribute {name!r}")
