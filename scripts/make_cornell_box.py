#!/usr/bin/env python3
"""Write the project's own Cornell box (scenes/cornell-box/scene.pbrt).

The geometry follows the layout of the classic Cornell box (a 2 x 2 x 2 room, a short and a
tall box turned towards each other, a square lamp under the ceiling), written from scratch here
so that the main job and the tests need nothing outside the repository. The lamp's spectrum is
the project's synthetic tri-band fluorescent spectrum (spectra/tri-band-fluorescent.spd), which
the evaluation replaces with the spectrum under study.

Usage: python scripts/make_cornell_box.py [OUTPUT]   (default: scenes/cornell-box/scene.pbrt)
"""
from __future__ import annotations

import math
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
    for name, geo in (("ShortBox", box(0.33, 0.37, 0.3, 0.6, -17.0)),
                      ("TallBox", box(-0.33, -0.28, 0.3, 1.2, 17.0))):
        text.append(f"AttributeBegin  # {name}\n{white}")
        text.append(mesh(*geo) + "AttributeEnd\n")
    light = quad((-0.24, 1.98, -0.22), (0.23, 1.98, -0.22), (0.23, 1.98, 0.16), (-0.24, 1.98, 0.16))
    text += [
        "AttributeBegin  # Light: emits downwards (the side its triangles' normal faces)",
        'AreaLightSource "diffuse"',
        '    "spectrum L" "../../spectra/tri-band-fluorescent.spd"',
        '    "float scale" [ 16 ]',
        'Material "diffuse" "rgb reflectance" [ 0 0 0 ]',
        mesh(*light) + "AttributeEnd",
    ]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(text) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
