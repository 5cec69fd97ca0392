"""Which parameter of a pbrt-v4 light directive carries its spectrum (design §5.4).

pbrt-v4's point-like lights (``point``, ``spot``, ``goniometric``, ``projection``) take their
spectrum as the intensity ``I``; every other ``LightSource`` and every ``AreaLightSource``
takes the radiance ``L``. The scene readers (``scene_spectra``) and the evaluation's scene
editor (``evaluation.scene_edit``) ask this module; the renderer asks its own
``pbrt::EmissionParameterName``, and tests/data/emitter-parameters.csv pins both.
"""
from __future__ import annotations

__all__ = ["INTENSITY_LIGHTS", "emission_parameter"]

#: LightSource types whose spectrum parameter is the intensity I rather than the radiance L.
INTENSITY_LIGHTS = frozenset({"point", "spot", "goniometric", "projection"})


def emission_parameter(directive: str, light_type: str) -> str:
    """``"I"`` or ``"L"``: the name of the spectrum parameter of a ``directive``
    (``LightSource`` or ``AreaLightSource``) of type ``light_type``."""
    return "I" if directive == "LightSource" and light_type in INTENSITY_LIGHTS else "L"
