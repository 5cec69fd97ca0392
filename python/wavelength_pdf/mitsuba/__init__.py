"""Table-driven wavelength sampling in Mitsuba 3's spectral variants (design §1, §5).

Usage::

    import wavelength_pdf.mitsuba as wpm   # before the first llvm variant is set
    import mitsuba as mi
    mi.set_variant("llvm_ad_spectral")
    wpm.register()
    scene = mi.load_dict({..., "sensor": {"type": "perspective",
                                          "srf": {"type": "wavelength_table", "filename": "t.csv"}}})

In XML: ``<texture type="wavelength_table" name="srf"><string name="filename" value="t.csv"/>
</texture>`` inside the ``<sensor>``. Mitsuba's own ``mitsuba`` command cannot load a plugin
written in Python; ``python -m wavelength_pdf mitsuba scene.xml -o out.exr`` (or
``wavelength-pdf mitsuba``, Mitsuba's flags ``-m -o -D -s -a -t``) renders such a scene, and
:func:`load_file` / :func:`load_dict` load one in a spectral variant with the plugin registered,
with a clear error for an RGB or mono variant (:mod:`wavelength_pdf.mitsuba.scenes`).

Cost: in the llvm and cuda variants the plugin's Python code runs once, while Dr.Jit traces
the kernel, and costs nothing per sample. In ``scalar_spectral`` Mitsuba calls it, in Python,
once per sample: renders take 5-7 times as long as with Mitsuba's default sampling. Use
``llvm_ad_spectral`` (the same images to Mitsuba's own scalar-llvm agreement, wavelength_table/README.md).

Emission sampling, no table file (design §1.7): ``scene_dict["sensor"]["srf"] =
wpm.emission_srf(mi.load_dict(scene_dict))`` gives the sensor a ``wavelength_table`` built from
the scene's own emitters (:mod:`wavelength_pdf.mitsuba.emission`). See :mod:`wavelength_pdf.mitsuba.texture` for why the plugin
is a texture used as the sensor's ``srf``.

Importing this package sets ``DRJIT_LIBLLVM_PATH`` to Debian's LLVM 19 when it is unset and the
library exists (Mitsuba 3.9's llvm variants abort with LLVM 14); it has to happen before an
llvm variant is first set (:mod:`wavelength_pdf.mitsuba.llvm`).
"""
from __future__ import annotations

import importlib

from wavelength_pdf.mitsuba.llvm import ensure_llvm_path

ensure_llvm_path()

from wavelength_pdf.mitsuba.emission import (  # noqa: E402
    EmissionError, emission_srf, emission_table, emitted_power)
from wavelength_pdf.mitsuba.sampler import TableSampler, defensive_mixture  # noqa: E402
from wavelength_pdf.mitsuba.texture import PLUGIN_NAME, texture_class  # noqa: E402
from wavelength_pdf.mitsuba.scenes import PluginError, load_dict, load_file, render_file  # noqa: E402

__all__ = ["register", "registered_variants", "TableSampler", "defensive_mixture", "PLUGIN_NAME",
           "texture_class", "ensure_llvm_path", "emission_srf", "emission_table", "emitted_power",
           "EmissionError", "load_file", "load_dict", "render_file", "PluginError"]

_REGISTERED: set[str] = set()


def _spectral_variants() -> list[str]:
    import mitsuba

    return [v for v in mitsuba.variants() if "spectral" in v]


def register(variants: str | list[str] | None = None) -> list[str]:
    """Register the ``wavelength_table`` texture in Mitsuba's spectral variants.

    Parameters
    ----------
    variants : str, list of str or None
        Variants to register in; None: every spectral variant this Mitsuba build has whose
        backend can start here (a cuda variant without a CUDA device is left out).

    Returns
    -------
    list of str
        The variants the plugin is registered in (this call's and earlier ones).

    Raises
    ------
    ValueError
        A named variant is not spectral, or does not exist.
    """
    import mitsuba

    if variants is None:
        names, strict = _spectral_variants(), False
    else:
        names, strict = ([variants] if isinstance(variants, str) else list(variants)), True
    for name in names:
        if name in _REGISTERED:
            continue
        if "spectral" not in name or name not in mitsuba.variants():
            raise ValueError(f"{name}: not a spectral variant of this Mitsuba build "
                             f"(spectral variants: {', '.join(_spectral_variants())})")
        try:
            m = importlib.import_module(f"mitsuba.{name}")
            cls = texture_class(m)
        except (ImportError, RuntimeError) as e:  # e.g. cuda_* without a CUDA device
            if strict:
                raise
            continue
        m.register_texture(PLUGIN_NAME, lambda props, cls=cls: cls(props))
        _REGISTERED.add(name)
    _stand_in_for_current_variant(mitsuba)
    return sorted(_REGISTERED)


def _stand_in_for_current_variant(mitsuba) -> None:
    """In the current variant, when it is not spectral, a ``wavelength_table`` that refuses
    to load with the reason (RGB and mono variants sample no wavelengths) instead of
    Mitsuba's "Plugin not found"."""
    from wavelength_pdf.mitsuba.scenes import not_spectral_message

    current = mitsuba.variant()
    if not current or "spectral" in current:
        return
    m = importlib.import_module(f"mitsuba.{current}")

    class NotSpectral(m.Texture):
        def __init__(self, props):
            m.Texture.__init__(self, props)
            raise ValueError(not_spectral_message(current))

    m.register_texture(PLUGIN_NAME, lambda props: NotSpectral(props))


def registered_variants() -> list[str]:
    """The variants ``register`` has registered the plugin in."""
    return sorted(_REGISTERED)
