"""The package's build backend: setuptools' own, with a wheel's intermediate folders outside the
checkout.

setuptools builds a wheel by copying the package into ``build/lib`` (then ``build/bdist.*``)
and zipping what it finds there, and it never empties those folders. In this repository
``build/`` is the renderer's CMake folder, and a module deleted or renamed since the previous
``pip install .`` or ``pip wheel .`` was still in ``build/lib`` and shipped again. Here every
wheel is built under a temporary folder of its own, removed afterwards, so a wheel holds what
the sources hold now and ``build/`` is left to CMake.

Every other hook (sdist, metadata, editable installs, which setuptools already builds in
temporary folders) is setuptools' unchanged. ``pyproject.toml`` names this module
(``backend-path``) and ``MANIFEST.in`` puts it in the sdist, whose wheel is built by it too.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F401,F403  (the hooks not redefined below)

#: distutils reads this extra configuration file after setup.cfg; it is the one way to give
#: the ``build`` command its folder when the build is started through PEP 517.
_EXTRA_CONFIG = "DIST_EXTRA_CONFIG"


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    """setuptools' ``build_wheel`` with ``build_base`` in a fresh temporary folder."""
    with tempfile.TemporaryDirectory(prefix="wavelength-pdf-wheel-") as tmp:
        config = Path(tmp, "build.cfg")
        # A user's own extra configuration file would be replaced, not merged: say so.
        if os.environ.get(_EXTRA_CONFIG):
            raise RuntimeError(f"${_EXTRA_CONFIG} is set ({os.environ[_EXTRA_CONFIG]}); this "
                               "project's build backend sets it itself: unset it to build")
        config.write_text(f"[build]\nbuild_base = {Path(tmp, 'build')}\n", encoding="utf-8")
        os.environ[_EXTRA_CONFIG] = str(config)
        try:
            return _setuptools.build_wheel(wheel_directory, config_settings, metadata_directory)
        finally:
            del os.environ[_EXTRA_CONFIG]
