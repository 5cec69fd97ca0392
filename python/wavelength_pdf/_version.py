"""The package's version (pyproject.toml's; tests/wavelength_pdf/test_public_api.py keeps the two
equal), in a module of its own so that the modules that write it into their output import
nothing above them."""
__version__ = "0.1.0"
