#!/usr/bin/env python3
"""Write the wavelength-sampling benchmark's own scenes (pbrt-v4 format) into scenes/benchmark/.

Each scene is lit by spiky lamps, the case the wavelength tables are for. Every spectrum is
written inline (``"spectrum L" [ lambda value ... ]``): lamps from colour-science's CIE
illuminants (CIE 15:2018 / CIE 204 data), surface colours from its ColorChecker reflectances
("ColorChecker N Ohta"), filters and the prism's glass from the formulas below. The output is
deterministic: the same colour-science data give the same bytes.

  colorchecker          the 24 ColorChecker patches on a dark board under one area light,
                        direct light only (maxdepth 1); the lamp is a flat placeholder that
                        the benchmark replaces.
  lamp-room             three bays of one room, each under its own ceiling lamp: high-pressure
                        sodium (CIE HP1), white LED (CIE LED-B3), metal halide (CIE HP3).
                        Rendered with its own lamps.
  prism                 a prism spectrograph: a fluorescent lamp (CIE FL11 placeholder)
                        behind a slit, a collimating lens, a dense-flint (SCHOTT N-SF11)
                        prism and a focusing lens spread the lamp's lines into coloured
                        bands on a white screen.
  tinted-glass          a lantern of green and amber "diffusetransmission" panes around one
                        lamp (flat placeholder), lighting a white corner and two objects.
  window-room           daylight through a window (sun: "distant", CIE D50; sky: "infinite",
                        CIE D65) and a fluorescent ceiling luminaire (CIE FL11) in one room.
                        Rendered with its own lights.
  night-street          a street at night: sodium street lamps (HP1), white LED street lamps
                        (LED-B4) and a metal-halide floodlight (HP4) on a shop sign.
                        Rendered with its own lights.
  glass-of-water-water  a water body (water.ply) for ../shared's glass-of-water scene, whose
                        own water mesh is missing; wavelength_pdf.evaluation.glass_of_water
                        writes a copy of that scene with it in place.

Why HP3 and HP4 for metal halide: CIE 15:2018 describes HP1 as a standard high-pressure
sodium lamp (1959 K), HP2 as a colour-enhanced sodium lamp (2506 K), HP3 and HP4 as metal
halide lamps (3144 K and 4002 K) and HP5 as a ceramic metal halide lamp (4039 K); the
correlated colour temperatures of colour-science's data agree. HP3 is the lamp-room's metal
halide: it has the most line-dominated spectrum of the three (peak 4.3 times its mean) and a
colour distinct from the 4102 K LED beside it. The street's floodlight is the cooler HP4,
typical of floodlighting.

Usage: .venv/bin/python scripts/make_benchmark_scenes.py [--out DIR] [--only NAME ...]
(default DIR: scenes/benchmark; run from anywhere). ``--help`` lists the options.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "scenes" / "benchmark"
HEADER = "written by scripts/make_benchmark_scenes.py (CC0); spectra: CIE data via colour-science"

# ---------------------------------------------------------------------------------------
# Spectra


def _colour():
    import colour  # imported lazily: --help works without it

    return colour


def illuminant(name: str, lo: float = 380.0, hi: float = 780.0) -> tuple[np.ndarray, np.ndarray]:
    """A CIE illuminant from colour-science, at its published samples inside [lo, hi]."""
    sd = _colour().SDS_ILLUMINANTS[name]
    lam, val = np.asarray(sd.wavelengths, float), np.asarray(sd.values, float)
    keep = (lam >= lo) & (lam <= hi)
    return lam[keep], val[keep]


def colorchecker() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The 24 ColorChecker reflectances (chart order), extended to 360-830 nm.

    The published data cover 380-780 nm; pbrt-v4 reads a tabulated spectrum as 0 outside
    its samples, so each is given its end values at 360 and 830 nm (the renderer samples
    360-830 nm).
    """
    out = {}
    for name, sd in _colour().SDS_COLOURCHECKERS["ColorChecker N Ohta"].items():
        out[name] = extend(np.asarray(sd.wavelengths, float), np.asarray(sd.values, float))
    return out


def extend(lam: np.ndarray, val: np.ndarray, lo: float = 360.0, hi: float = 830.0):
    """lam/val with the end values repeated at lo and hi."""
    if lam[0] > lo:
        lam, val = np.concatenate([[lo], lam]), np.concatenate([[val[0]], val])
    if lam[-1] < hi:
        lam, val = np.concatenate([lam, [hi]]), np.concatenate([val, [val[-1]]])
    return lam, val


def smooth_curve(fn, lo: float = 360.0, hi: float = 830.0, step: float = 5.0):
    lam = np.arange(lo, hi + step / 2, step)
    return lam, np.array([fn(x) for x in lam])


def green_filter(lam: float) -> float:
    """Transmittance of a green glass: a smooth band around 530 nm (peak 0.78, ~90 nm wide)
    on a 2% floor, with a weak red leak above 680 nm as coloured glasses have."""
    band = 0.76 * math.exp(-0.5 * ((lam - 530.0) / 38.0) ** 2)
    leak = 0.12 / (1.0 + math.exp(-(lam - 720.0) / 15.0))
    return 0.02 + band + leak


def amber_filter(lam: float) -> float:
    """Transmittance of an amber glass: a smooth long-pass edge at 575 nm (3% below, 86% above)."""
    return 0.03 + 0.83 / (1.0 + math.exp(-(lam - 575.0) / 10.0))


# SCHOTT N-SF11 dense flint: Sellmeier coefficients from SCHOTT's optical glass data sheet
# (n^2 - 1 = sum B_i l^2 / (l^2 - C_i), l in micrometres); n_d = 1.78472, Abbe number 25.68.
NSF11_B = (1.73759695, 0.313747346, 1.89878101)
NSF11_C = (0.013188707, 0.0623068142, 155.23629)


def nsf11_index(lam_nm: float) -> float:
    l2 = (lam_nm / 1000.0) ** 2
    return math.sqrt(1.0 + sum(b * l2 / (l2 - c) for b, c in zip(NSF11_B, NSF11_C)))


# ---------------------------------------------------------------------------------------
# Text


def num(x: float) -> str:
    s = f"{x:.6g}"
    return "0" if s in ("-0", "0") else s


def spectrum(param: str, lam, val, per_line: int = 8, indent: str = "    ") -> str:
    """``"spectrum param" [ l v l v ... ]``, per_line pairs to a line."""
    pairs = [f"{num(l)} {num(v)}" for l, v in zip(lam, val)]
    lines = ["  ".join(pairs[i:i + per_line]) for i in range(0, len(pairs), per_line)]
    if len(lines) == 1:
        return f'"spectrum {param}" [ {lines[0]} ]'
    body = ("\n" + indent + "  ").join(lines)
    return f'"spectrum {param}" [\n{indent}  {body} ]'


FLAT = (np.array([380.0, 780.0]), np.array([1.0, 1.0]))


class Mesh:
    """Triangles collected from quads and boxes, written as one "trianglemesh"."""

    def __init__(self) -> None:
        self.points: list[tuple[float, float, float]] = []
        self.normals: list[tuple[float, float, float]] = []   # per vertex, or none
        self.indices: list[int] = []

    def quad(self, p0, p1, p2, p3) -> "Mesh":
        """A planar quad; its normal is (p1 - p0) x (p2 - p0) (pbrt-v4's triangle normal)."""
        n = len(self.points)
        self.points += [tuple(map(float, p)) for p in (p0, p1, p2, p3)]
        self.indices += [n, n + 1, n + 2, n, n + 2, n + 3]
        return self

    def tri(self, p0, p1, p2) -> "Mesh":
        """A triangle; its normal is (p1 - p0) x (p2 - p0)."""
        n = len(self.points)
        self.points += [tuple(map(float, p)) for p in (p0, p1, p2)]
        self.indices += [n, n + 1, n + 2]
        return self

    def rect(self, center, normal, up, width: float, height: float) -> "Mesh":
        """A width x height rectangle at center whose normal is `normal`, `up` along its height."""
        c, n, u = (np.asarray(v, float) for v in (center, normal, up))
        n = n / np.linalg.norm(n)
        u = u - n * np.dot(u, n)
        u /= np.linalg.norm(u)
        r = np.cross(u, n)
        hw, hh = r * width / 2, u * height / 2
        return self.quad(c - hw - hh, c + hw - hh, c + hw + hh, c - hw + hh)

    def box(self, lo, hi, angle_deg: float = 0.0, pivot=None, bottom: bool = False) -> "Mesh":
        """An axis-aligned box [lo, hi] turned by angle_deg about the vertical axis through
        pivot (its centre by default), faces outward; no bottom face unless asked."""
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        pv = (lo + hi) / 2 if pivot is None else np.asarray(pivot, float)
        a = math.radians(angle_deg)
        ca, sa = math.cos(a), math.sin(a)

        def P(x, y, z):
            dx, dz = x - pv[0], z - pv[2]
            return (pv[0] + ca * dx + sa * dz, y, pv[2] - sa * dx + ca * dz)

        x0, y0, z0 = lo
        x1, y1, z1 = hi
        self.quad(P(x0, y1, z0), P(x0, y1, z1), P(x1, y1, z1), P(x1, y1, z0))  # top (+y)
        self.quad(P(x0, y0, z1), P(x1, y0, z1), P(x1, y1, z1), P(x0, y1, z1))  # +z
        self.quad(P(x1, y0, z0), P(x0, y0, z0), P(x0, y1, z0), P(x1, y1, z0))  # -z
        self.quad(P(x1, y0, z1), P(x1, y0, z0), P(x1, y1, z0), P(x1, y1, z1))  # +x
        self.quad(P(x0, y0, z0), P(x0, y0, z1), P(x0, y1, z1), P(x0, y1, z0))  # -x
        if bottom:
            self.quad(P(x0, y0, z0), P(x1, y0, z0), P(x1, y0, z1), P(x0, y0, z1))  # -y
        return self

    def text(self, indent: str = "") -> str:
        pts = " ".join(num(v) for p in self.points for v in p)
        idx = " ".join(str(i) for i in self.indices)
        nrm = ""
        if self.normals:
            nrm = f'{indent}    "normal N" [ ' + " ".join(num(round(v, 5)) for p in self.normals for v in p) + " ]\n"
        return (f'{indent}Shape "trianglemesh"\n{indent}    "point3 P" [ {pts} ]\n' + nrm +
                f'{indent}    "integer indices" [ {idx} ]\n')


def block(comment: str, *lines: str) -> str:
    """AttributeBegin ... AttributeEnd with a comment."""
    body = "".join(l if l.endswith("\n") else l + "\n" for l in lines)
    body = "".join("    " + l + "\n" if l else "\n" for l in body.rstrip("\n").split("\n"))
    return f"AttributeBegin  # {comment}\n{body}AttributeEnd\n\n"


def diffuse(refl) -> str:
    """A diffuse material with a tabulated reflectance (lam, val) or a float."""
    if isinstance(refl, (int, float)):
        return f'Material "diffuse" "spectrum reflectance" [ 360 {num(refl)} 830 {num(refl)} ]'
    return 'Material "diffuse" ' + spectrum("reflectance", *refl)


def area_light(comment: str, spec, scale: float, shape: str) -> str:
    """An emitting shape: its L spectrum normalized to 1 nit times scale (pbrt-v4)."""
    return block(comment,
                 f'AreaLightSource "diffuse"\n    {spectrum("L", *spec, indent="    ")}\n    "float scale" [ {num(scale)} ]',
                 'Material "diffuse" "spectrum reflectance" [ 360 0 830 0 ]',
                 shape)


def header(title: str, lines: list[str], *, eye, look, up=(0, 1, 0), fov: float, res=(320, 240),
           spp: int = 64, maxdepth: int = 5, filename: str) -> str:
    text = f"# {title}\n# {HEADER}.\n" + "".join(f"# {l}\n" for l in lines)
    text += (f'LookAt {" ".join(num(v) for v in eye)}  {" ".join(num(v) for v in look)}  {" ".join(num(v) for v in up)}\n'
             f'Camera "perspective" "float fov" [ {num(fov)} ]\n'
             f'Sampler "sobol" "integer pixelsamples" [ {spp} ]\n'
             f'Integrator "path" "integer maxdepth" [ {maxdepth} ]\n'
             f'PixelFilter "gaussian"\n'
             f'Film "rgb" "string filename" [ "{filename}" ]\n'
             f'    "integer xresolution" [ {res[0]} ] "integer yresolution" [ {res[1]} ]\n'
             "WorldBegin\n\n")
    return text


# ---------------------------------------------------------------------------------------
# colorchecker

def scene_colorchecker() -> dict[str, str]:
    cc = colorchecker()
    patch, gap = 1.0, 0.25
    cols, rows = 6, 4
    width, height = cols * patch + (cols - 1) * gap, rows * patch + (rows - 1) * gap
    border = 0.45
    text = header("ColorChecker: the 24 patches of colour-science's \"ColorChecker N Ohta\" on a dark board.",
                  ["One diffuse area light (a flat placeholder spectrum, replaced by the benchmark) behind",
                   "the camera, direct light only (maxdepth 1): a colour-critical scene with little path noise."],
                  eye=(0, 0, 14), look=(0, 0, 0), fov=25, maxdepth=1, filename="colorchecker.exr")
    board = Mesh().rect((0, 0, 0), (0, 0, 1), (0, 1, 0), width + 2 * border, height + 2 * border)
    text += block("Board: dark neutral, 4% reflectance", diffuse(0.04), board.text())
    for i, (name, refl) in enumerate(cc.items()):
        r, c = divmod(i, cols)
        # pbrt's camera is left-handed: looking down -z, world +x is on the image's left.
        x = width / 2 - patch / 2 - c * (patch + gap)
        y = height / 2 - patch / 2 - r * (patch + gap)
        m = Mesh().rect((x, y, 0.005), (0, 0, 1), (0, 1, 0), patch, patch)
        text += block(f"Patch {i + 1}: {name}", diffuse(refl), m.text())
    lamp = Mesh().rect((0, 5, 20), (0, -5, -20), (0, 1, 0), 4, 4)
    text += area_light("Lamp: 4 x 4 behind and above the camera, facing the chart (placeholder spectrum)",
                       FLAT, 75, lamp.text())
    return {"scene.pbrt": text}


# ---------------------------------------------------------------------------------------
# prism

LENS_ETA = 1.5          # the lenses' glass, dispersion-free so that only the prism spreads the light


def lens_mesh(center, axis, focal: float, radius: float, edge: float = 0.01, rings: int = 8,
              segments: int = 40) -> Mesh:
    """A symmetric biconvex spherical lens of the given (thick-lens) focal length and aperture
    radius, centred at center with its optical axis along axis: smooth vertex normals, a
    cylindrical rim, closed, facing out."""
    n = LENS_ETA
    # Thick symmetric lens: 1/f = (n - 1) (2 / R - (n - 1) t / (n R^2)), so
    # R = (n - 1) f (1 + sqrt(1 - t / (n f))), with the thickness t = 2 sag(R) + edge:
    # a few fixed-point steps from the thin lens.
    R = 2 * (n - 1) * focal
    for _ in range(50):
        t = 2 * (R - math.sqrt(R * R - radius * radius)) + edge
        R = (n - 1) * focal * (1 + math.sqrt(1 - t / (n * focal)))
    sag = R - math.sqrt(R * R - radius * radius)
    t = 2 * sag + edge
    prof = []
    for k in range(rings + 1):
        rho = radius * k / rings
        prof.append((rho, -t / 2 + (R - math.sqrt(R * R - rho * rho))))
    for k in range(rings, -1, -1):
        rho = radius * k / rings
        prof.append((rho, t / 2 - (R - math.sqrt(R * R - rho * rho))))
    verts, norms, tris = revolve(prof, {rings, rings + 1}, segments)
    ax = np.asarray(axis, float) / np.linalg.norm(axis)
    e1 = np.array([0.0, 1.0, 0.0])
    e1 = e1 - ax * np.dot(e1, ax)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(e1, ax)
    c = np.asarray(center, float)
    m = Mesh()
    m.points = [tuple(c + x * e1 + y * ax + z * e2) for x, y, z in verts]
    m.normals = [tuple(x * e1 + y * ax + z * e2) for x, y, z in norms]
    m.indices = [i for tri in tris for i in tri]
    return m


def scene_prism() -> dict[str, str]:
    cc = colorchecker()
    # A prism spectrograph (top view: x to the right, z towards the camera): a short vertical
    # slit, lit from behind by the lamp, stands at the focus of a collimating lens; the
    # parallel beam crosses the prism at minimum deviation for 589 nm and is bent towards -z;
    # a second lens focuses each wavelength's beam to its own image of the slit on a white
    # screen. A point of the screen sees the lamp through the whole second lens, so a path
    # tracer's diffuse bounce from the screen finds it far more often than through a bare
    # slit (where the lamp's angular size would have to be the spectral resolution).
    slit_x, slit_w, slit_h, axis_y = -2.0, 0.03, 0.24, 0.9
    f1, f2, r1, r2 = 1.2, 1.6, 0.24, 0.35
    prism_x, side, ph = 0.0, 1.3, 1.0
    n0 = nsf11_index(589.0)
    apex = math.radians(60.0)
    dev = 2 * math.asin(n0 * math.sin(apex / 2)) - apex
    d_in = np.array([1.0, 0.0, 0.0])
    d_out = np.array([math.cos(dev), 0.0, -math.sin(dev)])
    inside = (d_in + d_out) / np.linalg.norm(d_in + d_out)   # the ray inside, parallel to the base
    away = np.array([-inside[2], 0.0, inside[0]])            # from the base towards the apex
    if np.dot(away, d_out - d_in) > 0:
        away = -away
    h = side * math.sqrt(3) / 2
    tri = [away * (2 * h / 3), -away * (h / 3) - inside * (side / 2), -away * (h / 3) + inside * (side / 2)]
    # The entry face (apex to the base corner the beam meets first) has its midpoint on the
    # axis at prism_x: the beam crosses the prism's middle and leaves through the exit
    # face's midpoint.
    entry_mid, exit_mid = (tri[0] + tri[1]) / 2, (tri[0] + tri[2]) / 2
    prism_c = np.array([prism_x, 0.0, 0.0]) - entry_mid
    tri = [prism_c + p for p in tri]
    exit_pt = prism_c + exit_mid + np.array([0, axis_y, 0])
    y0, y1 = axis_y - ph / 2, axis_y + ph / 2
    prism = Mesh()
    a, b, c = tri
    if np.cross(b - a, c - a)[1] < 0:    # counter-clockwise seen from above: faces point out
        b, c = c, b
    lo = [p + np.array([0, y0, 0]) for p in (a, b, c)]
    hi = [p + np.array([0, y1, 0]) for p in (a, b, c)]
    prism.tri(hi[0], hi[1], hi[2]).tri(lo[0], lo[2], lo[1])
    for i in range(3):
        j = (i + 1) % 3
        prism.quad(lo[i], lo[j], hi[j], hi[i])
    lens1 = lens_mesh((slit_x + f1, axis_y, 0), d_in, f1, r1)
    l2_c = exit_pt + d_out * 0.45
    lens2 = lens_mesh(l2_c, d_out, f2, r2)
    screen_c = l2_c + d_out * f2
    screen = Mesh().rect(screen_c, -d_out, (0, 1, 0), 1.2, 0.9)
    stand = Mesh().box(screen_c + np.array([-0.04, -axis_y, -0.04]), screen_c + np.array([0.04, -0.45, 0.04]))
    eye = tuple(screen_c + np.array([1.5, 0.55, 2.4]))
    look = tuple(screen_c + np.array([-0.4, -0.1, 0.6]))

    glass = [(l, nsf11_index(l)) for l in range(360, 831, 10)]
    text = header("Prism: a dispersive N-SF11 glass prism spreading a fluorescent lamp's light onto a white screen.",
                  ["A prism spectrograph: the lamp behind a slit, a collimating lens (f = 1.2), the prism at",
                   f"minimum deviation for 589 nm ({math.degrees(dev):.1f} degrees), a lens (f = 1.6) focusing each",
                   "wavelength's image of the slit onto the screen: the lamp's lines become coloured bands",
                   "(0.4 degrees, 0.011 units on the screen, per 10 nm near 589 nm). The lamp and a dim fill light carry",
                   "placeholder spectra (CIE FL11 and flat) that the benchmark replaces. The prism's glass: SCHOTT",
                   "N-SF11, n(lambda) from its Sellmeier coefficients (SCHOTT optical glass data sheet), every 10",
                   "nm; the lenses: eta 1.5, without dispersion. A caustic through six refractions: slow to converge."],
                  eye=eye, look=look, fov=32, maxdepth=10, spp=256, filename="prism.exr")
    text += block("Floor: grey", diffuse(cc["neutral 5 (.70 D)"]),
                  Mesh().rect((0, 0, -1), (0, 1, 0), (0, 0, -1), 16, 12).text())
    wall = Mesh()
    zw, hw = 1.5, 2.0
    sz0, sz1 = -slit_w / 2, slit_w / 2
    sy0, sy1 = axis_y - slit_h / 2, axis_y + slit_h / 2
    wall.rect((slit_x, hw / 2, (sz1 + zw) / 2), (1, 0, 0), (0, 1, 0), zw - sz1, hw)
    wall.rect((slit_x, hw / 2, (sz0 - zw) / 2), (1, 0, 0), (0, 1, 0), zw + sz0, hw)
    wall.rect((slit_x, sy0 / 2, 0), (1, 0, 0), (0, 1, 0), slit_w, sy0)
    wall.rect((slit_x, (sy1 + hw) / 2, 0), (1, 0, 0), (0, 1, 0), slit_w, hw - sy1)
    text += block(f"Slit wall: dark grey, a slit {num(slit_w)} wide and {num(slit_h)} tall",
                  diffuse(cc["neutral 3.5 (1.05 D)"]), wall.text())
    text += block("Prism: SCHOTT N-SF11 dense flint",
                  'Material "dielectric" ' + spectrum("eta", [g[0] for g in glass], [round(g[1], 5) for g in glass]),
                  prism.text())
    lens_mat = f'Material "dielectric" "float eta" [ {num(LENS_ETA)} ]'
    text += block("Collimating lens (f = 1.2), the slit at its focus", lens_mat, lens1.text())
    text += block("Focusing lens (f = 1.6), the screen at its focus", lens_mat, lens2.text())
    text += block("Screen: white, on a stand", diffuse(cc["white 9.5 (.05 D)"]), screen.text(), stand.text())
    tube = Mesh().rect((slit_x - 0.25, axis_y, 0), (1, 0, 0), (0, 1, 0), 0.2, 0.4)
    text += area_light("Lamp: behind the slit, facing it (placeholder: CIE FL11)",
                       illuminant("FL11"), 100, tube.text())
    fill = Mesh().rect((0.5, 4.0, 0.0), (0, -1, 0), (0, 0, -1), 2, 2)
    text += area_light("Fill light: dim, from above, so that the room is not black (placeholder spectrum)",
                       FLAT, 4.0, fill.text())
    return {"scene.pbrt": text}


# ---------------------------------------------------------------------------------------
# lamp-room

def scene_lamp_room() -> dict[str, str]:
    cc = colorchecker()
    W, H, D0, D1 = 4.5, 2.7, -3.0, 5.0       # room: x in [-W, W], y in [0, H], z in [D0, D1]
    # pbrt's camera is left-handed: looking down -z, world +x is on the image's left, so the
    # left bay is at x > 0.
    bays = [(3.0, "Left bay", "HP1", "high-pressure sodium (CIE HP1)", 30.0),
            (0.0, "Middle bay", "LED-B3", "white LED (CIE LED-B3)", 30.0),
            (-3.0, "Right bay", "HP3", "metal halide (CIE HP3)", 30.0)]
    text = header("Lamp room: three bays of one room, each under its own kind of lamp.",
                  ["Left: high-pressure sodium (CIE HP1); middle: white LED (CIE LED-B3); right: metal halide",
                   "(CIE HP3, a quartz metal-halide lamp of 3144 K; see the generator's docstring for the choice).",
                   "Full-height partitions between the bays keep each lamp's light mostly in its own bay.",
                   "Surfaces: ColorChecker reflectances. Rendered with its own lamps (not replaced)."],
                  eye=(0, 1.55, 4.7), look=(0, 1.05, -3), fov=44, filename="lamp-room.exr")
    walls = {
        "Floor": ((0, 0, (D0 + D1) / 2), (0, 1, 0), (0, 0, -1), 2 * W, D1 - D0, cc["dark skin"]),
        "Ceiling": ((0, H, (D0 + D1) / 2), (0, -1, 0), (0, 0, -1), 2 * W, D1 - D0, cc["white 9.5 (.05 D)"]),
        "Left wall": ((-W, H / 2, (D0 + D1) / 2), (1, 0, 0), (0, 1, 0), D1 - D0, H, cc["neutral 8 (.23 D)"]),
        "Right wall": ((W, H / 2, (D0 + D1) / 2), (-1, 0, 0), (0, 1, 0), D1 - D0, H, cc["neutral 8 (.23 D)"]),
        "Front wall": ((0, H / 2, D1), (0, 0, -1), (0, 1, 0), 2 * W, H, cc["neutral 6.5 (.44 D)"]),
    }
    for name, (c, n, up, w, h, refl) in walls.items():
        text += block(name, diffuse(refl), Mesh().rect(c, n, up, w, h).text())
    back = [("Back wall, left bay: blue sky", 3.0, cc["blue sky"]),
            ("Back wall, middle bay: light skin", 0.0, cc["light skin"]),
            ("Back wall, right bay: foliage", -3.0, cc["foliage"])]
    for name, x, refl in back:
        text += block(name, diffuse(refl), Mesh().rect((x, H / 2, D0), (0, 0, 1), (0, 1, 0), 3.0, H).text())
    part = Mesh().box((-1.55, 0, D0), (-1.45, H, -0.4)).box((1.45, 0, D0), (1.55, H, -0.4))
    text += block("Partitions: white, full height, from the back wall to z = -0.4",
                  diffuse(cc["white 9.5 (.05 D)"]), part.text())
    objects = [
        ("Left bay: red box", Mesh().box((3.1, 0, -2.4), (3.9, 0.8, -1.6), 20), cc["red"]),
        ("Left bay: cyan box", Mesh().box((2.3, 0, -1.2), (2.9, 0.45, -0.6), -15), cc["cyan"]),
        ("Middle bay: yellow box", Mesh().box((0.1, 0, -2.3), (0.9, 1.0, -1.5), -25), cc["yellow"]),
        ("Middle bay: purplish blue box", Mesh().box((-0.9, 0, -1.2), (-0.3, 0.5, -0.6), 10), cc["purplish blue"]),
        ("Right bay: green box", Mesh().box((-3.9, 0, -2.4), (-3.1, 0.7, -1.6), -10), cc["green"]),
        ("Right bay: magenta box", Mesh().box((-2.8, 0, -1.1), (-2.2, 0.55, -0.5), 30), cc["magenta"]),
    ]
    for name, mesh, refl in objects:
        text += block(name, diffuse(refl), mesh.text())
    spheres = [("Left bay: orange sphere", (2.2, 0.35, -2.2), 0.35, cc["orange"]),
               ("Middle bay: white sphere", (-0.7, 0.4, -2.2), 0.4, cc["white 9.5 (.05 D)"]),
               ("Right bay: orange yellow sphere", (-3.6, 0.3, -0.9), 0.3, cc["orange yellow"])]
    for name, c, r, refl in spheres:
        text += block(name, diffuse(refl), f"Translate {num(c[0])} {num(c[1])} {num(c[2])}",
                      f'Shape "sphere" "float radius" [ {num(r)} ]')
    for x, where, lamp, what, scale in bays:
        m = Mesh().rect((x, H - 0.01, -1.4), (0, -1, 0), (0, 0, -1), 0.7, 0.7)
        text += area_light(f"{where} lamp: {what}, 0.7 x 0.7 under the ceiling, facing down",
                           illuminant(lamp), scale, m.text())
    return {"scene.pbrt": text}


# ---------------------------------------------------------------------------------------
# tinted-glass

def scene_tinted_glass() -> dict[str, str]:
    cc = colorchecker()
    green, amber = smooth_curve(green_filter), smooth_curve(amber_filter)
    pane_r = 0.06                       # a frosted pane's diffuse reflectance
    text = header("Tinted glass: a lantern of green and amber translucent panes around one lamp.",
                  ["The panes are \"diffusetransmission\" (frosted coloured glass: 6% diffuse reflectance, a",
                   "smooth spectral transmittance: green, a band around 530 nm; amber, a long-pass edge at",
                   "575 nm); the lamp inside (a flat placeholder spectrum, replaced by the benchmark) lights the",
                   "white corner and two white objects only through them. The lantern's front (+z) and -x",
                   "panes are green, its +x and back (-z) panes amber."],
                  eye=(2.5, 1.75, 4.4), look=(-0.35, 0.6, -0.3), fov=42, filename="tinted-glass.exr")
    white = cc["white 9.5 (.05 D)"]
    text += block("Floor: light grey", diffuse(cc["neutral 8 (.23 D)"]),
                  Mesh().rect((0, 0, 0), (0, 1, 0), (0, 0, -1), 12, 12).text())
    text += block("Back wall: white", diffuse(white), Mesh().rect((0, 2.5, -2.2), (0, 0, 1), (0, 1, 0), 12, 5).text())
    text += block("Side wall: white", diffuse(white), Mesh().rect((-3.0, 2.5, 0), (1, 0, 0), (0, 1, 0), 12, 5).text())
    # The lantern: 0.8 x 1.0 x 0.8, panes between a white base and lid.
    x0, x1, z0, z1, y0, y1 = -0.4, 0.4, -0.4, 0.4, 0.08, 1.08
    frame = Mesh().box((x0 - 0.02, 0, z0 - 0.02), (x1 + 0.02, y0, z1 + 0.02))
    frame.box((x0 - 0.02, y1, z0 - 0.02), (x1 + 0.02, y1 + 0.06, z1 + 0.02), bottom=True)
    text += block("Lantern base and lid: white", diffuse(white), frame.text())
    ym = (y0 + y1) / 2
    green_panes = Mesh().rect((0, ym, z1), (0, 0, 1), (0, 1, 0), x1 - x0, y1 - y0)     # +z, faces the camera
    green_panes.rect((x0, ym, 0), (-1, 0, 0), (0, 1, 0), z1 - z0, y1 - y0)              # -x
    amber_panes = Mesh().rect((x1, ym, 0), (1, 0, 0), (0, 1, 0), z1 - z0, y1 - y0)     # +x, seen by the camera
    amber_panes.rect((0, ym, z0), (0, 0, -1), (0, 1, 0), x1 - x0, y1 - y0)               # -z
    def pane(t):
        return ('Material "diffusetransmission"\n    ' + spectrum("reflectance", [360, 830], [pane_r, pane_r]) +
                "\n    " + spectrum("transmittance", *t, indent="    "))
    text += block("Green panes (+z, facing the camera, and -x)", pane(green), green_panes.text())
    text += block("Amber panes (+x, seen by the camera, and -z)", pane(amber), amber_panes.text())
    text += block("White sphere on the amber side (+x)", diffuse(white),
                  "Translate 1.45 0.45 -0.5", 'Shape "sphere" "float radius" [ 0.45 ]')
    text += block("White box on the green side (-x)", diffuse(white),
                  Mesh().box((-1.9, 0, 0.1), (-1.2, 0.7, 0.8), 25).text())
    text += area_light("Lamp: a small sphere inside the lantern (placeholder spectrum)", FLAT, 40.0,
                       f"Translate 0 {num(ym)} 0\n" + 'Shape "sphere" "float radius" [ 0.1 ]')
    return {"scene.pbrt": text}


# ---------------------------------------------------------------------------------------
# window-room

def wall_with_hole(x: float, z0: float, z1: float, y0: float, y1: float,
                   hole: tuple[float, float, float, float], normal_x: float) -> Mesh:
    """The wall x = const over [z0, z1] x [y0, y1] without the opening (hz0, hz1, hy0, hy1),
    as four rectangles facing normal_x (+1 or -1)."""
    hz0, hz1, hy0, hy1 = hole
    m = Mesh()
    n = (normal_x, 0, 0)
    for (a0, a1, b0, b1) in ((z0, z1, y0, hy0), (z0, z1, hy1, y1), (z0, hz0, hy0, hy1), (hz1, z1, hy0, hy1)):
        m.rect((x, (b0 + b1) / 2, (a0 + a1) / 2), n, (0, 1, 0), a1 - a0, b1 - b0)
    return m


def scene_window_room() -> dict[str, str]:
    cc = colorchecker()
    W, H, D0, D1 = 3.0, 2.8, -4.0, 3.0         # room: x in [-W, W], y in [0, H], z in [D0, D1]
    hole = (-3.4, -1.2, 0.8, 2.3)               # the window in the +x wall (image left): z0, z1, y0, y1
    text = header("Window room: daylight through a window and a fluorescent luminaire in one room.",
                  ["Outside: the sun (\"distant\", CIE D50, from above the window) and a uniform sky",
                   "(\"infinite\", CIE D65); the sunlight falls through the window onto the floor at the back.",
                   "Inside: a ceiling luminaire with a CIE FL11 (narrow tri-band) tube over the desk on the other",
                   "side. Both spectra are cut to 380-780 nm. Rendered with its own lights (not replaced)."],
                  eye=(0.3, 1.6, 2.8), look=(0.0, 0.95, -4.0), fov=50, filename="window-room.exr")
    walls = {
        "Floor: wood (dark skin)": ((0, 0, (D0 + D1) / 2), (0, 1, 0), (0, 0, -1), 2 * W, D1 - D0, cc["dark skin"]),
        "Ceiling: white": ((0, H, (D0 + D1) / 2), (0, -1, 0), (0, 0, -1), 2 * W, D1 - D0, cc["white 9.5 (.05 D)"]),
        "Back wall: light skin": ((0, H / 2, D0), (0, 0, 1), (0, 1, 0), 2 * W, H, cc["light skin"]),
        "Front wall: neutral 8": ((0, H / 2, D1), (0, 0, -1), (0, 1, 0), 2 * W, H, cc["neutral 8 (.23 D)"]),
        "Wall without window (image right): neutral 8": ((-W, H / 2, (D0 + D1) / 2), (1, 0, 0), (0, 1, 0), D1 - D0, H,
                                                         cc["neutral 8 (.23 D)"]),
    }
    for name, (c, n, up, w, h, refl) in walls.items():
        text += block(name, diffuse(refl), Mesh().rect(c, n, up, w, h).text())
    text += block("Window wall (+x, image left): neutral 8, with an opening 2.2 wide and 1.5 tall",
                  diffuse(cc["neutral 8 (.23 D)"]), wall_with_hole(W, D0, D1, 0, H, hole, -1).text())
    reveal = Mesh()
    hz0, hz1, hy0, hy1 = hole
    t = 0.2                                       # wall thickness: the reveals and the sill
    reveal.rect((W + t / 2, hy0, (hz0 + hz1) / 2), (0, 1, 0), (1, 0, 0), hz1 - hz0, t)
    reveal.rect((W + t / 2, hy1, (hz0 + hz1) / 2), (0, -1, 0), (1, 0, 0), hz1 - hz0, t)
    reveal.rect((W + t / 2, (hy0 + hy1) / 2, hz0), (0, 0, 1), (0, 1, 0), t, hy1 - hy0)
    reveal.rect((W + t / 2, (hy0 + hy1) / 2, hz1), (0, 0, -1), (0, 1, 0), t, hy1 - hy0)
    text += block("Window reveals and sill: white", diffuse(cc["white 9.5 (.05 D)"]), reveal.text())
    furniture = [
        ("Sofa by the window (blue)", Mesh().box((1.2, 0, -3.8), (2.8, 0.45, -2.9)).box((1.2, 0.45, -3.9), (2.8, 0.9, -3.6)),
         cc["purplish blue"]),
        ("Low table (orange)", Mesh().box((1.9, 0, -0.5), (2.7, 0.4, 0.3), 10), cc["orange"]),
        ("Desk under the luminaire (neutral 6.5)", Mesh().box((-2.9, 0, -2.8), (-1.9, 0.75, -1.0)), cc["neutral 6.5 (.44 D)"]),
        ("Bookshelf (moderate red)", Mesh().box((-2.95, 0, -0.6), (-2.55, 1.9, 0.6)), cc["moderate red"]),
        ("Box on the desk (yellow green)", Mesh().box((-2.7, 0.75, -2.4), (-2.3, 1.05, -2.0), 20), cc["yellow green"]),
    ]
    for name, mesh, refl in furniture:
        text += block(name, diffuse(refl), mesh.text())
    text += block("Sphere on the floor in the sunlight (white)", diffuse(cc["white 9.5 (.05 D)"]),
                  "Translate 0.9 0.3 -2.6", 'Shape "sphere" "float radius" [ 0.3 ]')
    lum = Mesh().rect((-2.1, H - 0.01, -1.9), (0, -1, 0), (0, 0, -1), 0.6, 2.0)
    text += area_light("Luminaire over the desk: CIE FL11, 0.6 x 2.0 under the ceiling, facing down",
                       illuminant("FL11"), 10.0, lum.text())
    text += block("Sun: CIE D50, illuminance 10 (relative units), through the window",
                  'LightSource "distant" "point3 from" [ 2.2 1.6 0.45 ] "point3 to" [ 0 0 0 ]\n    ' +
                  spectrum("L", *illuminant("D50"), indent="    ") + '\n    "float scale" [ 10 ]')
    text += block("Sky: CIE D65, uniform",
                  'LightSource "infinite"\n    ' + spectrum("L", *illuminant("D65"), indent="    ") +
                  '\n    "float scale" [ 1 ]')
    return {"scene.pbrt": text}


# ---------------------------------------------------------------------------------------
# night-street

def scene_night_street() -> dict[str, str]:
    cc = colorchecker()
    # The street runs along z; the camera stands on the road looking down it (-z). World +x
    # is on the image's left (pbrt's left-handed camera).
    road, walk, z_near, z_far = 4.0, 2.5, 6.0, -40.0
    text = header("Night street: sodium street lamps, white LED street lamps and a metal-halide floodlit sign.",
                  ["Left side (+x): three high-pressure sodium lamps (CIE HP1) on poles; right side (-x): two",
                   "white LED lamps (CIE LED-B4); a metal-halide floodlight (CIE HP4, a spot light) on the",
                   "left facade lights a shop sign. No sky. Rendered with its own lamps (not replaced)."],
                  eye=(0.6, 1.8, 5.0), look=(-0.2, 1.9, -20.0), fov=45, filename="night-street.exr")
    zl = z_far - z_near
    zc = (z_near + z_far) / 2
    text += block("Road: asphalt", diffuse(0.07), Mesh().rect((0, 0, zc), (0, 1, 0), (0, 0, -1), 2 * road, -zl).text())
    walks = Mesh()
    for sgn in (1, -1):
        x0, x1 = sorted((sgn * road, sgn * (road + walk)))
        walks.box((x0, 0, z_far), (x1, 0.15, z_near))
    text += block("Pavements: concrete", diffuse(cc["neutral 5 (.70 D)"]), walks.text())
    fac = road + walk
    facades = [
        ("Left facade: brick (moderate red)", fac, -1, cc["moderate red"]),
        ("Right facade: render (light skin)", -fac, 1, cc["light skin"]),
    ]
    for name, x, n, refl in facades:
        text += block(name, diffuse(refl),
                      Mesh().rect((x, 6.0, zc), (n, 0, 0), (0, 1, 0), -zl, 12.0).text())
    # Shop fronts and doors: darker panels just in front of the facades.
    fronts = Mesh()
    for z in (-2.5, -10.5, -27.0):
        fronts.rect((fac - 0.01, 1.6, z), (-1, 0, 0), (0, 1, 0), 4.0, 2.6)
    for z in (-8.0, -21.0):
        fronts.rect((-fac + 0.01, 1.2, z), (1, 0, 0), (0, 1, 0), 1.2, 2.2)
    text += block("Shop windows and doors: dark", diffuse(cc["black 2 (1.5 D)"]), fronts.text())
    # Halfway between two sodium lamps, so that the floodlight is what lights it.
    sign = Mesh().rect((fac - 0.02, 3.6, -10.5), (-1, 0, 0), (0, 1, 0), 5.0, 1.2)
    text += block("Shop sign: light grey board (lit by the metal-halide floodlight)", diffuse(cc["neutral 8 (.23 D)"]),
                  sign.text())
    cars = [
        ("Parked car: blue", (road - 2.1, 0, -12.8), (road - 0.3, 1.4, -8.5), cc["blue"]),
        ("Parked car: yellow", (-road + 0.3, 0, -13.5), (-road + 2.1, 1.4, -9.2), cc["yellow"]),
        ("Parked van: white", (road - 2.3, 0, -26.0), (road - 0.3, 2.2, -20.5), cc["neutral 8 (.23 D)"]),
    ]
    for name, lo, hi, refl in cars:
        text += block(name, diffuse(refl), Mesh().box(lo, hi).text())
    bins = Mesh().box((-road - 0.9, 0.15, -4.0), (-road - 0.4, 1.1, -3.5)).box((-road - 0.9, 0.15, -3.3), (-road - 0.4, 1.1, -2.8))
    text += block("Bins: green", diffuse(cc["green"]), bins.text())
    poles = Mesh()
    sodium = [-4.0, -17.0, -30.0]
    leds = [-10.5, -23.5]
    for z in sodium:
        poles.box((road + 0.45, 0.15, z - 0.08), (road + 0.6, 6.2, z + 0.08))
        poles.box((road - 1.2, 6.2, z - 0.06), (road + 0.6, 6.35, z + 0.06))
    for z in leds:
        poles.box((-road - 0.6, 0.15, z - 0.08), (-road - 0.45, 6.2, z + 0.08))
        poles.box((-road - 0.6, 6.2, z - 0.06), (-road + 1.2, 6.35, z + 0.06))
    text += block("Lamp poles: dark grey", diffuse(cc["neutral 3.5 (1.05 D)"]), poles.text())
    hp1, led = illuminant("HP1"), illuminant("LED-B4")
    for i, z in enumerate(sodium):
        m = Mesh().rect((road - 0.9, 6.19, z), (0, -1, 0), (0, 0, -1), 0.6, 0.35)
        text += area_light(f"Sodium street lamp {i + 1} (CIE HP1), left side, facing down", hp1, 600.0, m.text())
    for i, z in enumerate(leds):
        m = Mesh().rect((-road + 0.9, 6.19, z), (0, -1, 0), (0, 0, -1), 0.6, 0.3)
        text += area_light(f"LED street lamp {i + 1} (CIE LED-B4), right side, facing down", led, 700.0, m.text())
    text += block("Metal-halide floodlight (CIE HP4) on the left facade, aimed up at the shop sign",
                  'LightSource "spot" "point3 from" [ ' + f"{num(fac - 1.3)} 2.3 -10.5" + ' ] "point3 to" [ ' +
                  f"{num(fac)} 3.6 -10.5" + ' ]\n    "float coneangle" [ 40 ] "float conedeltaangle" [ 10 ]\n    ' +
                  spectrum("I", *illuminant("HP4"), indent="    ") + '\n    "float scale" [ 14 ]')
    return {"scene.pbrt": text}


# ---------------------------------------------------------------------------------------
# glass-of-water-water

# The inner surface of the glass in ../shared/scenes/glass-of-water (models/Mesh013.ply, a
# surface of revolution about the y axis, 128 segments), as (radius, height) from the axis
# outwards: read from that mesh's vertices whose normals face the cavity (the flat bottom at
# y = 0.3317-0.3359, then the fillet and the slightly curved, widening wall up to the rim at
# y = 5.41). Heights in the fillet are the highest vertex within each radius band and radii
# on the wall the row's smallest, so the curve lies on the cavity's side of the glass's vertices.
GLASS_INNER = [
    (0.0, 0.3359), (0.60, 0.3359), (0.64, 0.3352), (0.72, 0.3395), (0.78, 0.3461), (0.84, 0.3570),
    (0.90, 0.3719), (0.945, 0.3917), (0.983, 0.4242), (1.013, 0.4776), (1.044, 0.5597),
    (1.0756, 0.6787), (1.1109, 0.8425), (1.1529, 1.059), (1.2047, 1.337), (1.2694, 1.683),
    (1.3437, 2.081), (1.4243, 2.512), (1.5079, 2.960), (1.5913, 3.406), (1.6711, 3.834),
    (1.7441, 4.224), (1.8070, 4.561), (1.8564, 4.826), (1.8942, 5.027),
]
WATER_GAP = 0.01        # between the water and the glass (the glass's facets lie 0.0008 inside its vertices)
WATER_LEVEL = 4.3       # the flat surface: the ice cube in the glass (y 2.68-4.54) floats in it
MENISCUS = (0.06, 0.15)  # height and width of the rise at the wall
WATER_SEGMENTS = 64


def water_profile() -> tuple[list[tuple[float, float]], int]:
    """The water body's half cross-section (r, y), from the bottom centre round to the top
    centre, and the index of the crease (the meniscus' edge at the wall)."""
    g = np.array(GLASS_INNER, float)
    # Offset the glass curve by WATER_GAP towards the cavity (left of the outward walk).
    pts = []
    for i in range(len(g)):
        a, b = g[max(i - 1, 0)], g[min(i + 1, len(g) - 1)]
        t = (b - a) / np.linalg.norm(b - a)
        pts.append(g[i] + WATER_GAP * np.array([-t[1], t[0]]))
    pts[0][0] = 0.0
    hm, wm = MENISCUS
    top = WATER_LEVEL + hm
    wall = [p for p in pts if p[1] < top - 0.05]
    # The wall's radius at the meniscus' top, on the offset curve.
    ys = np.array([p[1] for p in pts])
    rs = np.array([p[0] for p in pts])
    r_edge = float(np.interp(top, ys, rs))
    prof = [(float(r), float(y)) for r, y in wall] + [(r_edge, top)]
    crease = len(prof) - 1
    for k in range(1, 9):
        s = k / 8
        prof.append((r_edge - wm * s, WATER_LEVEL + hm * (1 - s) ** 2))
    prof.append((0.0, WATER_LEVEL))
    return prof, crease


def revolve(prof: list[tuple[float, float]], creases: set[int], segments: int):
    """A closed surface of revolution about the y axis: vertices, normals and triangles.

    prof: (radius, height) points walking from a pole (radius 0) round the body's outline to
    the other pole, the body on the left of the walk (so that normals point out of it).
    Vertex normals average the two segments' normals, except at the indices in creases,
    where the point is split into two vertices of the same position (bit for bit) with each
    side's normal: the surface stays closed for the ray tests, which see positions.
    """
    seg = [np.array(prof[i + 1]) - np.array(prof[i]) for i in range(len(prof) - 1)]
    seg_n = [np.array([d[1], -d[0]]) / np.linalg.norm(d) for d in seg]
    rows = []
    for i, (r, y) in enumerate(prof):
        if i == 0:
            rows.append((r, y, (0.0, -1.0)))
        elif i == len(prof) - 1:
            rows.append((r, y, (0.0, 1.0)))
        elif i in creases:
            rows.append((r, y, tuple(seg_n[i - 1])))
            rows.append((r, y, tuple(seg_n[i])))
        else:
            n = seg_n[i - 1] + seg_n[i]
            rows.append((r, y, tuple(n / np.linalg.norm(n))))
    verts, norms, tris = [], [], []
    ring_start = []
    for k, (r, y, (nr, ny)) in enumerate(rows):
        ring_start.append(len(verts))
        count = 1 if r == 0.0 else segments
        for j in range(count):
            phi = 2 * math.pi * j / segments
            verts.append((r * math.cos(phi), y, r * math.sin(phi)))
            norms.append((nr * math.cos(phi), ny, nr * math.sin(phi)))

    def vid(k, j):
        return ring_start[k] if rows[k][0] == 0.0 else ring_start[k] + j % segments

    for k in range(len(rows) - 1):
        if rows[k][:2] == rows[k + 1][:2]:
            continue  # the two vertices of a crease
        for j in range(segments):
            a, b, c, d = vid(k, j), vid(k, j + 1), vid(k + 1, j + 1), vid(k + 1, j)
            for t in ((a, c, b), (a, d, c)):
                if len(set(t)) == 3:
                    tris.append(t)
    return verts, norms, tris


def water_mesh():
    """Vertices, normals and triangles of the water body: the profile revolved about y,
    creased where the meniscus meets the wall."""
    prof, crease = water_profile()
    return revolve(prof, {crease}, WATER_SEGMENTS)


def ply_text(verts, norms, tris) -> str:
    out = ["ply", "format ascii 1.0",
           "comment The water body for ../shared/scenes/glass-of-water; scripts/make_benchmark_scenes.py (CC0)",
           f"element vertex {len(verts)}", "property float x", "property float y", "property float z",
           "property float nx", "property float ny", "property float nz",
           f"element face {len(tris)}", "property list uchar int vertex_indices", "end_header"]
    out += [" ".join(num(round(c, 5)) for c in v) + " " + " ".join(num(round(c, 4)) for c in n)
            for v, n in zip(verts, norms)]
    out += ["3 " + " ".join(str(i) for i in t) for t in tris]
    return "\n".join(out) + "\n"



def scene_glass_of_water_water() -> dict[str, str]:
    verts, norms, tris = water_mesh()
    prof, _ = water_profile()
    readme = f"""# Water for the glass of water

`water.ply` is a water body for `../shared/scenes/glass-of-water/scene-v4.pbrt`, whose own water
mesh (`models/Mesh000.ply`) is missing (that scene renders the glass empty). Written by
`scripts/make_benchmark_scenes.py` (CC0); the shared scene itself is not part of this repository.

The mesh is closed: a surface of revolution about the glass's axis ({WATER_SEGMENTS} segments,
smooth vertex normals, pointing out of the water) that follows the glass's inner wall and bottom
{WATER_GAP} units inside them (the inner surface was read from the glass mesh,
`models/Mesh013.ply`), with a flat surface at y = {WATER_LEVEL} and a meniscus rising
{MENISCUS[0]} at the wall (the rim is at y = 5.41). It spans y = {prof[0][1]:.4f} to
{WATER_LEVEL + MENISCUS[0]:.2f}, radius up to {max(r for r, _ in prof):.4f}.

To put it into the scene, replace the commented-out water shape at the end of the world block
with the scene's own water material (a dielectric with eta 1.33, as in the original):

```
NamedMaterial "WaterAir"
Shape "plymesh" "string filename" [ "PATH/TO/scenes/benchmark/glass-of-water-water/water.ply" ]
```

or let the project write such a copy (paths made absolute, the shared scene left alone):

```python
from wavelength_pdf.evaluation.glass_of_water import with_water
with_water("../shared/scenes/glass-of-water/scene-v4.pbrt", "out/glass-of-water/scene.pbrt")
```

Known approximation: the ice cube in the glass (y 2.68-4.54) is partly under water, and the
scene describes its surfaces as ice-air interfaces (eta 1.31); where it is submerged the
physical interface would be ice-water (eta 1.31 / 1.33), which would need a material of its
own and a water body with the cube cut out. The air bubble near the bottom (`AirIce`,
eta 0.763) lies inside the water, as a bubble in water would.
"""
    return {"water.ply": ply_text(verts, norms, tris), "README.md": readme}


SCENES = {
    "colorchecker": scene_colorchecker,
    "lamp-room": scene_lamp_room,
    "prism": scene_prism,
    "tinted-glass": scene_tinted_glass,
    "window-room": scene_window_room,
    "night-street": scene_night_street,
    "glass-of-water-water": scene_glass_of_water_water,
}


def write_scene(name: str, out: Path) -> list[Path]:
    files = SCENES[name]()
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for fname, content in files.items():
        path = folder / fname
        path.write_text(content) if isinstance(content, str) else path.write_bytes(content)
        written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__,
        epilog="Scenes: " + ", ".join(SCENES) + ". Each goes to OUT/NAME/ (scene.pbrt and any mesh).",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output folder (default: {DEFAULT_OUT.relative_to(ROOT)})")
    ap.add_argument("--only", nargs="+", choices=list(SCENES), metavar="NAME", help="write only these scenes")
    args = ap.parse_args(argv)
    for name in args.only or SCENES:
        for path in write_scene(name, args.out):
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
