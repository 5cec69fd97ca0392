"""Where the renderer binary is: the one lookup that the optimizer (reading a scene's
emitters through pbrt, ``scene_spectra``) and the evaluation (rendering) share.

It sits below both, so that neither reaches into the other to find it.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

from wavelength_pdf.data import CHECKOUT, in_checkout

#: The checkout's own build of the renderer (scripts/setup.sh).
CHECKOUT_PBRT = CHECKOUT / "build" / "pbrt"
#: The renderer inside an installed wheel built with ``scripts/build_wheel.sh --with-pbrt``.
BUNDLED_PBRT = Path(__file__).resolve().parent / "_bin" / "pbrt"
#: Environment variable naming the renderer binary.
PBRT_ENV = "WAVELENGTH_PDF_PBRT"
#: The ways to get a renderer, for the message when none is found.
HOW_TO_GET_PBRT = (
    "give --pbrt PATH or set $" + PBRT_ENV + "; or, in a checkout, build it (bash scripts/setup.sh) and "
    "put it on PATH (cmake --install build --prefix ~/.local) or inside the wheel "
    "(bash scripts/build_wheel.sh --with-pbrt build/pbrt)")


class RendererNotFound(FileNotFoundError):
    """No renderer binary where :func:`find_pbrt` looked; the message lists the places."""


def find_pbrt(explicit: str | os.PathLike | None = None) -> Path:
    """The renderer binary: ``explicit`` (``--pbrt``), else ``$WAVELENGTH_PDF_PBRT``, else the
    checkout's ``build/pbrt``, else the installed wheel's own (``wavelength_pdf/_bin/pbrt``),
    else ``pbrt`` on ``PATH``.

    Raises
    ------
    RendererNotFound
        Nothing executable was found; the message lists every place looked at.
    """
    looked: list[str] = []

    def usable(p: Path) -> bool:
        return p.is_file() and os.access(p, os.X_OK)

    if explicit is not None:
        p = Path(explicit)
        if usable(p):
            return p
        raise RendererNotFound(f"--pbrt {p}: not an executable file")
    env = os.environ.get(PBRT_ENV)
    if env:
        if usable(Path(env)):
            return Path(env)
        looked.append(f"${PBRT_ENV}={env} (not an executable file)")
    else:
        looked.append(f"${PBRT_ENV} (not set)")
    if in_checkout():
        if usable(CHECKOUT_PBRT):
            return CHECKOUT_PBRT
        looked.append(f"{CHECKOUT_PBRT} (not built: bash scripts/setup.sh)")
    if usable(BUNDLED_PBRT):
        return BUNDLED_PBRT
    looked.append(f"{BUNDLED_PBRT} (this wheel was built without --with-pbrt)")
    on_path = shutil.which("pbrt")
    if on_path:
        return Path(on_path)
    looked.append("pbrt on PATH (none)")
    raise RendererNotFound("no renderer found; looked at: " + "; ".join(looked) + ". To get one: "
                           + HOW_TO_GET_PBRT)
