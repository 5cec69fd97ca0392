"""The shared glass-of-water scene with a water body in it.

``../shared/scenes/glass-of-water/scene-v4.pbrt`` lacks its water mesh (its water shape is
commented out), so it renders an empty glass. The project's water body
(``scenes/benchmark/glass-of-water-water/water.ply``, written by
``scripts/make_benchmark_scenes.py``) fits inside that glass; :func:`with_water` writes a copy
of the shared scene with it in place, made of the scene's own water material ("WaterAir", a
dielectric with eta 1.33). The shared scene is read, never copied into the repository.
"""
from __future__ import annotations

import re
from pathlib import Path

from wavelength_pdf.data import CHECKOUT
from wavelength_pdf.evaluation.scene_edit import edit_scene
from wavelength_pdf.spectra import SpectrumError

#: The water body in a checkout.
WATER_PLY = CHECKOUT / "scenes" / "benchmark" / "glass-of-water-water" / "water.ply"
#: The scene's name for its water material.
WATER_MATERIAL = "WaterAir"


def with_water(scene: str | Path, out: str | Path, *, water: str | Path = WATER_PLY,
               resolution: tuple[int, int] | float | None = None, maxdepth: int | None = None) -> Path:
    """Write a copy of the glass-of-water ``scene`` at ``out`` with the water body ``water`` in it.

    The copy is :func:`~wavelength_pdf.evaluation.scene_edit.edit_scene`'s (every file name made
    absolute, the emitters kept; ``resolution`` and ``maxdepth`` as there), followed by the water
    shape with the scene's ``"WaterAir"`` material, at the end of the world block.

    Raises
    ------
    SpectrumError
        (the evaluation's error for bad scene input) when the scene defines no ``"WaterAir"``
        material, already has a water shape (``Mesh000.ply`` not commented out), or the
        water mesh is missing.
    """
    scene, out, water = Path(scene), Path(out), Path(water).resolve()
    if not water.is_file():
        raise SpectrumError(f"{water}: the water mesh is missing (scripts/make_benchmark_scenes.py writes it)")
    text = scene.read_text(encoding="utf-8", errors="replace")
    if not re.search(r'^\s*MakeNamedMaterial\s+"' + WATER_MATERIAL + '"', text, re.M):
        raise SpectrumError(f'{scene}: no MakeNamedMaterial "{WATER_MATERIAL}" (is this the glass-of-water scene?)')
    if re.search(r'^[^#\n]*Mesh000\.ply', text, re.M):
        raise SpectrumError(f"{scene}: the scene already has its water shape (models/Mesh000.ply)")
    edit_scene(scene, None, out, resolution=resolution, maxdepth=maxdepth)
    body = out.read_text()
    if not body.endswith("\n"):
        body += "\n"
    body += ("\n# The water body: scenes/benchmark/glass-of-water-water (wavelength_pdf.evaluation.glass_of_water)\n"
             "AttributeBegin\n"
             f'    NamedMaterial "{WATER_MATERIAL}"\n'
             f'    Shape "plymesh" "string filename" [ "{water}" ]\n'
             "AttributeEnd\n")
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(body)
    tmp.replace(out)
    return out
