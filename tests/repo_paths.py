"""Where the repository, the renderer under test and the shared reference material are.

One place for every test: ``$WAVELENGTH_PDF_SHARED`` names the folder of shared reference
material (scenes, LSPDD spectra, reference tables), by default ``../shared`` beside the
repository; ``$PBRT_BIN`` the renderer, by default the checkout's ``build/pbrt``. Test modules
import these names from here (``from repo_paths import SHARED``), not from a ``conftest``, since each
test folder may have a conftest of its own.
"""
from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: The shared reference material (tests that need it skip cleanly when it is absent).
SHARED = Path(os.environ.get("WAVELENGTH_PDF_SHARED", REPO.parent / "shared"))
#: The renderer under test; PBRT_BIN overrides it (e.g. a developer's own build folder).
PBRT = Path(os.environ.get("PBRT_BIN", REPO / "build" / "pbrt"))
