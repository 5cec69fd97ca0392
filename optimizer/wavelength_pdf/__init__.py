"""Optimized wavelength-sampling densities for spectral rendering under spiky lamps.

The package finds four wavelength densities whose balance-heuristic estimator of a lamp's
colour varies as little as possible in CIEDE2000 (see ../shared/SPEC.md, sections 1-4).
"""

import jax

# The objective is optimized in float64: float32 gradients stop L-BFGS-B early.
jax.config.update("jax_enable_x64", True)

__version__ = "0.1.0"
