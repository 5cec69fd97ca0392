"""Loading and rendering Mitsuba 3 scenes that use the ``wavelength_table`` plugin, with errors
that say what is wrong instead of Mitsuba's "Plugin not found".

Mitsuba's own ``mitsuba`` command is a C++ program: it cannot load a plugin written in
Python, so a scene naming ``wavelength_table`` fails there. :func:`render_file` (and its
command line, ``python -m wavelength_pdf mitsuba SCENE.xml`` or ``wavelength-pdf mitsuba
SCENE.xml``, with Mitsuba's flags ``-m``, ``-o``, ``-D``, ``-s``, ``-a``, ``-t``) renders an XML
scene with the plugin registered.

Two mistakes give only "Plugin not found" in plain Mitsuba: a variant that is not spectral
(the plugin samples wavelengths, which RGB and monochrome variants do not have) and a
forgotten :func:`wavelength_pdf.mitsuba.register`. :func:`load_file` and :func:`load_dict`
check the first and register the plugin themselves; :func:`register` also puts a stand-in in
the current variant when that one is not spectral, so that ``mi.load_dict`` says why.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

#: The variant the helpers use when none is set (the plugin runs compiled there, at no cost).
DEFAULT_VARIANT = "llvm_ad_spectral"


class PluginError(ValueError):
    """Mitsuba is set up so that the ``wavelength_table`` plugin cannot work (the message
    says why and what to do)."""


def not_spectral_message(variant: str) -> str:
    return (f"the Mitsuba variant {variant!r} is not spectral: the wavelength_table plugin samples "
            "wavelengths, which RGB and monochrome variants do not have; set a spectral variant "
            f"first, e.g. mi.set_variant({DEFAULT_VARIANT!r}) (or scalar_spectral, cuda_ad_spectral)")


def _mitsuba():
    try:
        import mitsuba
    except ImportError as e:
        raise PluginError("Mitsuba 3 is not installed (the package's mitsuba extra): pip install "
                          f"mitsuba ({e})") from None
    return mitsuba


def _resolver(mi):
    """Mitsuba's file resolver (``mi.file_resolver()`` from 3.6 on, the thread's before)."""
    return mi.file_resolver() if hasattr(mi, "file_resolver") else mi.Thread.thread().file_resolver()


def use_variant(variant: str | None = None) -> str:
    """Set ``variant`` (None: keep the current one, or :data:`DEFAULT_VARIANT` when none is
    set), check that it is spectral and register the plugin in it; returns the variant."""
    from wavelength_pdf.mitsuba import register

    mi = _mitsuba()
    if variant is None:
        variant = mi.variant() or DEFAULT_VARIANT
    if variant not in mi.variants():
        raise PluginError(f"no Mitsuba variant {variant!r} in this build; spectral ones: "
                          + ", ".join(v for v in mi.variants() if "spectral" in v))
    if "spectral" not in variant:
        raise PluginError(not_spectral_message(variant))
    if mi.variant() != variant:
        mi.set_variant(variant)
    register(variant)
    return variant


def _explained(e: Exception) -> Exception:
    """Mitsuba's error for the plugin, with the likely reason added."""
    text = str(e)
    if "wavelength_table" in text and "not found" in text:
        return PluginError(f"{text.strip()}\n(the wavelength_table plugin is not registered in "
                           "this variant: call wavelength_pdf.mitsuba.register() after "
                           "mi.set_variant(), or load scenes with wavelength_pdf.mitsuba.load_file"
                           " / load_dict, which register it)")
    return e


def load_file(path: str | Path, variant: str | None = None, **params: Any) -> Any:
    """``mi.load_file(path, **params)`` in a spectral ``variant`` (see :func:`use_variant`)
    with the plugin registered."""
    use_variant(variant)
    mi = _mitsuba()
    try:
        return mi.load_file(str(path), **params)
    except RuntimeError as e:
        raise _explained(e) from e


def load_dict(scene: Mapping[str, Any], variant: str | None = None) -> Any:
    """``mi.load_dict(scene)`` in a spectral ``variant`` with the plugin registered."""
    use_variant(variant)
    mi = _mitsuba()
    try:
        return mi.load_dict(dict(scene))
    except RuntimeError as e:
        raise _explained(e) from e


def render_file(path: str | Path, output: str | Path | None = None, *, variant: str | None = None,
                spp: int | None = None, sensor: int = 0, seed: int = 0,
                defines: Mapping[str, str] | None = None, search_paths: list[str] | None = None,
                threads: int | None = None) -> Path:
    """Render the XML scene ``path`` with the plugin registered, as Mitsuba's own command
    would (sensor ``sensor``, ``defines`` as its ``-D``), and write the image to ``output``
    (default: the scene's name with ``.exr``, beside the scene, as Mitsuba writes it).
    Returns the output path."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(2, "no such scene file", str(path))
    use_variant(variant)
    mi = _mitsuba()
    if threads is not None:
        import drjit as dr

        dr.set_thread_count(int(threads))
    resolver = _resolver(mi)
    resolver.prepend(str(path.resolve().parent))
    for extra in search_paths or []:
        resolver.append(str(extra))
    scene = load_file(path, **dict(defines or {}))
    sensors = scene.sensors()
    if not 0 <= sensor < len(sensors):
        raise PluginError(f"{path}: sensor index {sensor} out of range (the scene has {len(sensors)})")
    image = mi.render(scene, sensor=sensor, spp=spp or 0, seed=seed)
    out = Path(output) if output is not None else path.with_suffix(".exr")
    mi.util.write_bitmap(str(out), image)
    return out
