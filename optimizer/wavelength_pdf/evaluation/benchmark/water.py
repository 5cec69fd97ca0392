"""The glass of water with a water body (the evaluation scene's own mesh is missing).

The shared scene (``scenes/glass-of-water/scene-v4.pbrt``) renders the glass empty: its water
mesh was not distributed. The project's water body (``scenes/benchmark/glass-of-water-water/``,
made by ``scripts/make_benchmark_scenes.py``) fills the glass; it is added to a copy of the
scene with the scene's own water material (``NamedMaterial "WaterAir"``, a dielectric of index
1.33), so that the benchmark sees the refraction and caustics the scene was made for.
"""
from __future__ import annotations

from pathlib import Path

from wavelength_pdf.data import CHECKOUT

#: The project's water body.
WATER_MESH = CHECKOUT / "scenes" / "benchmark" / "glass-of-water-water" / "water.ply"
#: The scene's material for water (MakeNamedMaterial "WaterAir").
WATER_MATERIAL = "WaterAir"


def glass_with_water(scene: Path, folder: Path, mesh: Path = WATER_MESH) -> Path:
    """A copy of the glass-of-water ``scene`` in ``folder`` with the water body added before
    the scene's first ``AttributeBegin`` after its shapes (every file name made absolute)."""
    from wavelength_pdf.evaluation.scene_edit import edit_scene

    if not Path(mesh).is_file():
        raise FileNotFoundError(2, "the project's water body is missing (scripts/make_benchmark_scenes.py)",
                                str(mesh))
    copy = edit_scene(scene, None, Path(folder) / "scene.pbrt")
    text = copy.read_text()
    if f'MakeNamedMaterial "{WATER_MATERIAL}"' not in text:
        raise ValueError(f"{scene}: no material {WATER_MATERIAL!r} for the water body")
    water = (f'NamedMaterial "{WATER_MATERIAL}"\nShape "plymesh" "string filename" [ "{Path(mesh).resolve()}" ]\n')
    anchor = text.rfind("\nAttributeBegin")
    at = anchor + 1 if anchor >= 0 else len(text)
    copy.write_text(text[:at] + water + text[at:])
    return copy
