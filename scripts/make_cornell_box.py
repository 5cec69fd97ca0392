#!/usr/bin/env python3
"""Write the project's own Cornell box (scenes/cornell-box/scene.pbrt, and scene.xml for Mitsuba 3).

The geometry follows the layout of the classic Cornell box (a 2 x 2 x 2 room, a short and a
tall box turned towards each other, a square lamp under the ceiling), written from scratch here
so that the main job and the tests need nothing outside the repository. The lamp's spectrum is
the project's synthetic tri-band fluorescent spectrum (spectra/tri-band-fluorescent.spd), which
the evaluation replaces with the spectrum under study. A copy of it is written beside the scene,
which names it there: the folder is self-contained, so the installed package's copy of the
scene (``wavelength_pdf._data.cornell_box``) renders as the checkout's does.

The Mitsuba 3 version (scene.xml beside OUTPUT, meshes in meshes/*.obj) has the same
geometry, reflectances (the same sRGB values, which both renderers turn into spectra by
Jakob and Hanika's method), camera, filter and depth. Its lamp is a set of parameters:
``lamp_wavelengths`` and ``lamp_values`` (radiance, default: the tri-band spectrum scaled as
pbrt-v4 scales it) and ``lamp_luminance`` (pbrt's "scale", the lamp's Y), which
``wavelength-pdf evaluate --renderer mitsuba`` sets to the spectrum under study.

Usage: .venv/bin/python scripts/make_cornell_box.py [OUTPUT]   (default: scenes/cornell-box/scene.pbrt)
"""
from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path


def quad(p0, p1, p2, p3):
    """Two triangles (0 1 2, 0 2 3) of a planar quad, as (points, indices)."""
    return [p0, p1, p2, p3], [0, 1, 2, 0, 2, 3]


def box(cx: float, cz: float, half: float, height: float, angle_deg: float):
    """An upright box centred at (cx, 0, cz), turned by angle_deg about y, outward faces."""
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)

    def corner(x, z):
        return (cx + c * x - s * z, cz + s * x + c * z)

    base = [corner(-half, -half), corner(half, -half), corner(half, half), corner(-half, half)]
    lo = [(x, 0.0, z) for x, z in base]
    hi = [(x, height, z) for x, z in base]
    points, indices = [], []

    def add(face):
        n = len(points)
        points.extend(face)
        indices.extend([n + 0, n + 1, n + 2, n + 0, n + 2, n + 3])

    add([hi[0], hi[3], hi[2], hi[1]])  # top, facing +y
    for i in range(4):  # sides, counter-clockwise seen from outside
        j = (i + 1) % 4
        add([lo[i], lo[j], hi[j], hi[i]])
    return points, indices


def mesh(points, indices) -> str:
    p = " ".join(f"{v:.6g}" for pt in points for v in pt)
    i = " ".join(str(k) for k in indices)
    return f'Shape "trianglemesh"\n    "point3 P" [ {p} ]\n    "integer indices" [ {i} ]\n'


WHITE = (0.725, 0.71, 0.68)
LIGHT_SCALE = 16.0  # the lamp's luminance: pbrt's "scale" (pbrt-v4 normalizes L to 1 nit first)
MAX_DEPTH = 5  # pbrt's maxdepth; Mitsuba counts the camera segment too (max_depth = 6)
SPECTRUM = "spectra/tri-band-fluorescent.spd"


def light_quad():
    return quad((-0.24, 1.98, -0.22), (0.23, 1.98, -0.22), (0.23, 1.98, 0.16), (-0.24, 1.98, 0.16))


def obj(points, indices) -> str:
    """A Wavefront OBJ mesh (vertex indices from 1), flat triangles."""
    lines = [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in points]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in zip(indices[0::3], indices[1::3], indices[2::3])]
    return "\n".join(lines) + "\n"


def write_mitsuba(out: Path, walls: dict, boxes: list) -> None:
    """scene.xml and meshes/*.obj: the same Cornell box for Mitsuba 3 (see the module docstring)."""
    from wavelength_pdf.evaluation.render_mitsuba import lamp_radiance
    from wavelength_pdf.spectra import read_spd

    repo = Path(__file__).resolve().parents[1]
    lam, val = lamp_radiance(read_spd(repo / SPECTRUM, None, None), LIGHT_SCALE)
    meshes = out.parent / "meshes"
    meshes.mkdir(parents=True, exist_ok=True)
    shapes = []

    def shape(name: str, geo, inner: str) -> None:
        (meshes / f"{name}.obj").write_text(f"# {name} of the project's Cornell box (CC0)\n" + obj(*geo))
        shapes.append(f'    <shape type="obj" id="{name}">\n'
                      f'        <string name="filename" value="meshes/{name}.obj"/>\n'
                      f'        <boolean name="face_normals" value="true"/>\n{inner}    </shape>')

    def diffuse(rgb) -> str:
        # pbrt-v4's diffuse material reflects on both sides; Mitsuba's only on the front.
        return ('        <bsdf type="twosided">\n            <bsdf type="diffuse">\n'
                f'                <rgb name="reflectance" value="{rgb[0]}, {rgb[1]}, {rgb[2]}"/>\n'
                '            </bsdf>\n        </bsdf>\n')

    for name, (rgb, geo) in walls.items():
        shape(name, geo, diffuse(rgb))
    for name, geo in boxes:
        shape(name, geo, diffuse(WHITE))
    shape("Light", light_quad(),
          '        <emitter type="area">\n'
          '            <texture type="irregular" name="radiance">\n'
          '                <string name="wavelengths" value="$lamp_wavelengths"/>\n'
          '                <string name="values" value="$lamp_values"/>\n'
          '            </texture>\n'
          '        </emitter>\n'
          '        <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>\n')
    text = [
        '<?xml version="1.0" encoding="utf-8"?>',
        "<!-- The project's Cornell box for Mitsuba 3 (written by scripts/make_cornell_box.py; CC0).",
        "     The same room, boxes, reflectances, camera and light as scene.pbrt. The lamp's radiance",
        f"     defaults to {SPECTRUM} scaled as pbrt-v4 scales it: Y = lamp_luminance.",
        "     Table-driven wavelength sampling: add to the sensor",
        '       <texture type="wavelength_table" name="srf"><string name="filename" value="t.csv"/></texture>',
        "     after wavelength_pdf.mitsuba.register(). -->",
        '<scene version="3.0.0">',
        '    <default name="spp" value="64"/>',
        '    <default name="width" value="256"/>',
        '    <default name="height" value="256"/>',
        f'    <default name="max_depth" value="{MAX_DEPTH + 1}"/>',
        f'    <default name="lamp_luminance" value="{LIGHT_SCALE:g}"/>',
        '    <default name="lamp_wavelengths" value="' + ", ".join(f"{v:.10g}" for v in lam) + '"/>',
        '    <default name="lamp_values" value="' + ", ".join(f"{v:.10g}" for v in val) + '"/>',
        '    <integrator type="path">',
        '        <integer name="max_depth" value="$max_depth"/>',
        "    </integrator>",
        '    <sensor type="perspective">',
        '        <float name="fov" value="19.5"/>',
        '        <string name="fov_axis" value="smaller"/>',
        '        <transform name="to_world">',
        '            <lookat origin="0, 1, 6.8" target="0, 1, 0" up="0, 1, 0"/>',
        "        </transform>",
        '        <sampler type="independent">',
        '            <integer name="sample_count" value="$spp"/>',
        "        </sampler>",
        '        <film type="hdrfilm">',
        '            <integer name="width" value="$width"/>',
        '            <integer name="height" value="$height"/>',
        '            <string name="pixel_format" value="rgb"/>',
        '            <rfilter type="tent"/>',
        "        </film>",
        "    </sensor>",
        *shapes,
        "</scene>",
    ]
    xml = out.with_suffix(".xml")
    xml.write_text("\n".join(text) + "\n")
    print(f"wrote {xml} and {meshes}/")


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "scenes/cornell-box/scene.pbrt"
    walls = {
        # name: (reflectance rgb, quad seen from inside the room)
        "Floor": ((0.725, 0.71, 0.68), quad((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1))),
        "Ceiling": ((0.725, 0.71, 0.68), quad((1, 2, 1), (-1, 2, 1), (-1, 2, -1), (1, 2, -1))),
        "BackWall": ((0.725, 0.71, 0.68), quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1))),
        "LeftWall": ((0.63, 0.065, 0.05), quad((-1, 0, 1), (-1, 0, -1), (-1, 2, -1), (-1, 2, 1))),
        "RightWall": ((0.14, 0.45, 0.091), quad((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1))),
    }
    text = [
        "# The project's Cornell box (written by scripts/make_cornell_box.py; CC0).",
        "# A 2 x 2 x 2 room, two boxes, one spectral area light under the ceiling.",
        'Integrator "path" "integer maxdepth" [ 5 ]',
        "# Camera at (0, 1, 6.8) looking down -z (world-to-camera matrix; x keeps its sign).",
        "Transform [ 1 0 0 0  0 1 0 0  0 0 -1 0  0 -1 6.8 1 ]",
        'Sampler "independent" "integer pixelsamples" [ 64 ]',
        'PixelFilter "triangle" "float xradius" [ 1 ] "float yradius" [ 1 ]',
        'Film "rgb" "string filename" [ "cornell-box.exr" ]',
        '    "integer xresolution" [ 256 ] "integer yresolution" [ 256 ]',
        'Camera "perspective" "float fov" [ 19.5 ]',
        "WorldBegin",
        "",
    ]
    for name, (rgb, (pts, idx)) in walls.items():
        text.append(f'AttributeBegin  # {name}')
        text.append(f'Material "diffuse" "rgb reflectance" [ {rgb[0]} {rgb[1]} {rgb[2]} ]')
        text.append(mesh(pts, idx) + "AttributeEnd\n")
    white = 'Material "diffuse" "rgb reflectance" [ 0.725 0.71 0.68 ]'
    boxes = [("ShortBox", box(0.33, 0.37, 0.3, 0.6, -17.0)),
             ("TallBox", box(-0.33, -0.28, 0.3, 1.2, 17.0))]
    for name, geo in boxes:
        text.append(f"AttributeBegin  # {name}\n{white}")
        text.append(mesh(*geo) + "AttributeEnd\n")
    light = light_quad()
    text += [
        "AttributeBegin  # Light: emits downwards (the side its triangles' normal faces)",
        'AreaLightSource "diffuse"',
        f'    "spectrum L" "{Path(SPECTRUM).name}"',
        '    "float scale" [ 16 ]',
        'Material "diffuse" "rgb reflectance" [ 0 0 0 ]',
        mesh(*light) + "AttributeEnd",
    ]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(text) + "\n")
    # The lamp's spectrum beside the scene, byte for byte (the folder ships on its own).
    shutil.copyfile(Path(__file__).resolve().parents[1] / SPECTRUM, out.parent / Path(SPECTRUM).name)
    print(f"wrote {out} and {out.parent / Path(SPECTRUM).name}")
    write_mitsuba(out, walls, boxes)


if __name__ == "__main__":
    main()
