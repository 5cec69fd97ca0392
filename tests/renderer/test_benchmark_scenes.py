"""The benchmark's own scenes (scenes/benchmark/, written by scripts/make_benchmark_scenes.py).

- The generator reproduces the committed files byte for byte.
- Every scene renders small without a warning, to a finite image that is not black.
- The scenes rendered with their own lamps (lamp-room, night-street, window-room): switching
  one lamp off ("scale" 0) darkens the part of the picture it is meant to light, by much more
  than it darkens the rest; the sodium lamps make their part orange.
- colorchecker: each patch's rendered chromaticity is that of its reflectance under the flat
  placeholder lamp (direct light only), computed from the ColorChecker data.
- prism: the spectrum spreads across the screen: the two halves of the lit band differ in
  chromaticity (blue on one side, orange-red on the other).
- tinted-glass: the panes facing the camera are green and amber, the colours of their
  spectral transmittances.
- glass-of-water-water: the water mesh is closed, faces out, and lies inside the shared glass
  (below its rim, off its inner wall); the scene copy with it renders (needs ../shared).

Small renders at fixed seeds, so every assertion is deterministic; thresholds leave wide
margins around the measured values (noted with each).
"""
from __future__ import annotations

import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from repo_paths import REPO, SHARED  # noqa: E402

sys.path.insert(0, str(REPO / "python"))
from wavelength_pdf.evaluation.metrics import rgb_to_xyz  # noqa: E402
from wavelength_pdf.exr import read_rgb  # noqa: E402

SCENES_DIR = REPO / "scenes" / "benchmark"
GENERATOR = REPO / "scripts" / "make_benchmark_scenes.py"
RENDERED = ("colorchecker", "lamp-room", "prism", "tinted-glass", "window-room", "night-street")


def render(pbrt: Path, scene: Path, out: Path, *, res=(32, 24), spp: int = 16, seed: int = 1) -> np.ndarray:
    """XYZ image (h, w, 3) of ``scene``; fails on a non-zero exit or any warning."""
    cmd = [str(pbrt), "--quiet", "--nthreads", "2", "--resolution", f"{res[0]}x{res[1]}", "--spp", str(spp),
           "--seed", str(seed), "--outfile", str(out), str(scene)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, f"{' '.join(cmd)}:\n{proc.stderr}"
    assert "warning" not in proc.stderr, proc.stderr
    return rgb_to_xyz(read_rgb(out))


def with_scales(scene: Path, out: Path, zero: str) -> Path:
    """A copy of ``scene`` in its own folder whose light blocks with ``zero`` in their comment
    have "scale" 0."""
    text = scene.read_text()
    blocks = re.split(r"(?=AttributeBegin  # )", text)
    hits = 0
    for i, b in enumerate(blocks):
        first = b.split("\n", 1)[0]
        if zero in first and ("LightSource" in b):
            blocks[i] = re.sub(r'"float scale" \[ [^\]]+ \]', '"float scale" [ 0 ]', b)
            hits += 1
    assert hits, f"no light block matching {zero!r}"
    out.write_text("".join(blocks))
    return out


def chromaticity(xyz: np.ndarray) -> np.ndarray:
    s = xyz.sum(axis=-1, keepdims=True)
    return (xyz / s)[..., :2]


# ---------------------------------------------------------------------------------------


def test_generator_reproduces_the_committed_files(tmp_path):
    pytest.importorskip("colour")
    proc = subprocess.run([sys.executable, str(GENERATOR), "--out", str(tmp_path)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    made = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    committed = sorted(p.relative_to(SCENES_DIR) for p in SCENES_DIR.rglob("*") if p.is_file())
    assert made == committed
    for rel in made:
        assert (tmp_path / rel).read_bytes() == (SCENES_DIR / rel).read_bytes(), f"{rel} differs"


def test_generator_help():
    proc = subprocess.run([sys.executable, str(GENERATOR), "--help"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0
    for word in ("--out", "--only", "colorchecker", "glass-of-water-water"):
        assert word in proc.stdout


@pytest.mark.parametrize("name", RENDERED)
def test_scene_renders_finite_and_not_black(pbrt, tmp_path, name):
    scene = SCENES_DIR / name / "scene.pbrt"
    text = scene.read_text()
    assert 'Sampler "sobol"' in text
    # Every light's spectrum is written inline.
    lights = [b for b in text.split("AttributeBegin") if "LightSource" in b]
    assert lights
    for b in lights:
        assert re.search(r'"spectrum [LI]" \[', b), b[:200]
    img = render(pbrt, scene, tmp_path / "x.exr")
    assert np.all(np.isfinite(img))
    Y = img[..., 1]
    assert Y.mean() > 0.02, Y.mean()
    # Not a few lit pixels on black: at least a third of the picture is lit.
    assert (Y > 0.01).mean() > 0.33, (Y > 0.01).mean()


# ---------------------------------------------------------------------------------------
# Each lamp lights its part of the picture. Regions are (x0, x1, y0, y1) as fractions of the
# image (x to the right, y down), read off renders with each lamp off; the key names the light
# blocks switched off (by their comments). Measured at 48x36, 32 spp (light left in the region
# with the lamp off, and the median pixel's ratio elsewhere): lamp-room 0.002-0.005 vs
# 0.49-0.93; night-street sodium 0.1 vs 0.36 (it lights much of the street), LED 0.21 vs 0.75,
# metal halide 0.30-0.36 vs 0.99; window-room sun 0.21 vs 0.99, sky 0.17 vs 0.84, luminaire
# 0.07 vs 0.61.
LAMP_REGIONS = {
    "lamp-room": {
        "Left bay lamp": (0.0, 0.125, 1 / 6, 5 / 6),
        "Middle bay lamp": (0.375, 0.625, 1 / 6, 4 / 6),
        "Right bay lamp": (0.875, 1.0, 1 / 6, 5 / 6),
    },
    "night-street": {
        "Sodium street lamp": (0.0, 0.3, 2 / 3, 1.0),
        "LED street lamp": (0.75, 1.0, 1 / 6, 0.5),
        "Metal-halide floodlight": (1 / 12, 1 / 6, 0.28, 0.44),
    },
    "window-room": {
        "Sun:": (0.125, 0.5, 0.5, 5 / 6),
        "Sky:": (0.0, 0.125, 1 / 6, 0.5),
        "Luminaire over the desk": (0.625, 1.0, 1 / 6, 2 / 3),
    },
}
LAMP_RES, LAMP_SPP = (48, 36), 32


def region_mask(shape, region) -> np.ndarray:
    h, w = shape
    x0, x1, y0, y1 = region
    m = np.zeros((h, w), bool)
    m[int(round(y0 * h)):int(round(y1 * h)), int(round(x0 * w)):int(round(x1 * w))] = True
    return m


@pytest.mark.parametrize("name", sorted(LAMP_REGIONS))
def test_each_lamp_lights_its_part(pbrt, tmp_path, name):
    scene = SCENES_DIR / name / "scene.pbrt"
    on = render(pbrt, scene, tmp_path / "on.exr", res=LAMP_RES, spp=LAMP_SPP)[..., 1]
    for lamp, region in LAMP_REGIONS[name].items():
        copy = with_scales(scene, scene.parent / f"_test_{tmp_path.name}.pbrt", lamp)
        try:
            off = render(pbrt, copy, tmp_path / "off.exr", res=LAMP_RES, spp=LAMP_SPP)[..., 1]
        finally:
            copy.unlink()
        mask = region_mask(on.shape, region)
        own = off[mask].sum() / on[mask].sum()
        # The rest of the picture: the median pixel's ratio (the lamps themselves, seen
        # directly, would dominate a sum).
        lit = ~mask & (on > 1e-3)
        rest = float(np.median(off[lit] / on[lit]))
        assert own < 0.5, f"{name}: {lamp} off leaves {own:.2f} of its region's light"
        assert own < 0.5 * rest, f"{name}: {lamp} off darkens its region ({own:.2f}) not much more than the rest ({rest:.2f})"


@pytest.mark.parametrize("name, region", [("lamp-room", (0.0, 0.125, 1 / 6, 5 / 6)),
                                          ("night-street", (0.0, 0.3, 2 / 3, 1.0))])
def test_sodium_light_is_orange(pbrt, tmp_path, name, region):
    """CIE HP1 (1959 K, x = 0.533): its part of the picture is orange, x > 0.48 (measured 0.52-0.53;
    the white LEDs and daylight are at x = 0.31-0.38)."""
    img = render(pbrt, SCENES_DIR / name / "scene.pbrt", tmp_path / "x.exr", res=LAMP_RES, spp=LAMP_SPP)
    xy = chromaticity(img[region_mask(img.shape[:2], region)].sum(axis=0))
    assert xy[0] > 0.48, xy


def mesh_points(block: str) -> np.ndarray:
    return np.array([float(v) for v in re.search(r'"point3 P" \[ ([^\]]+)\]', block).group(1).split()]).reshape(-1, 3)


def test_colorchecker_patches_have_their_colours(pbrt, tmp_path):
    """Each patch's chromaticity is that of its reflectance times the flat placeholder lamp
    (380-780 nm), integrated with the CIE 1931 functions: within 0.006 in xy (measured: at
    most 0.002; a patch swapped with its neighbour is 0.02-0.2 off)."""
    colour = pytest.importorskip("colour")
    scene = SCENES_DIR / "colorchecker" / "scene.pbrt"
    text = scene.read_text()
    w, h = 96, 72
    img = render(pbrt, scene, tmp_path / "cc.exr", res=(w, h), spp=64)
    eye_z = float(re.search(r"^LookAt \S+ \S+ (\S+)", text, re.M).group(1))
    fov = float(re.search(r'"float fov" \[ (\S+) \]', text).group(1))
    half_h = eye_z * np.tan(np.radians(fov / 2))          # the chart is at z = 0, facing the camera
    half_w = half_h * w / h
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    lam = np.arange(380, 781, 1.0)
    xbar = np.array([np.interp(lam, cmfs.wavelengths, cmfs.values[:, k]) for k in range(3)])
    names = list(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"])
    blocks = re.findall(r"AttributeBegin  # Patch (\d+): ([^\n]+)\n(.*?)AttributeEnd", text, re.S)
    assert [int(b[0]) for b in blocks] == list(range(1, 25))
    assert [b[1] for b in blocks] == names
    worst = 0.0
    for _, name, block in blocks:
        c = mesh_points(block).mean(axis=0)
        # pbrt's camera is left-handed: world +x appears on the image's left.
        col = int((0.5 - c[0] / (2 * half_w)) * w)
        row = int((0.5 - c[1] / (2 * half_h)) * h)
        got = chromaticity(img[row - 1:row + 2, col - 1:col + 2].reshape(-1, 3).sum(axis=0))
        rl = np.array([float(v) for v in re.search(r'"spectrum reflectance" \[([^\]]+)\]', block).group(1).split()])
        refl = np.interp(lam, rl[0::2], rl[1::2])
        want = chromaticity(xbar @ refl)
        worst = max(worst, float(np.abs(got - want).max()))
        assert np.abs(got - want).max() < 0.006, f"{name}: rendered xy {got}, expected {want}"
    print(f"worst xy error {worst:.4f}")


def test_prism_spreads_the_spectrum_across_the_screen(pbrt, tmp_path):
    """Seen face-on (the camera moved in front of the screen, the fill light off), the lit band
    on the screen runs from orange-red to blue: the chromaticity of its two halves (by column)
    differs by more than 0.15 in x (measured 0.29), the blue half having the larger z.
    Few paths reach the lamp through six refractions, so the halves are sums over the band."""
    scene = SCENES_DIR / "prism" / "scene.pbrt"
    text = scene.read_text()
    block = text[text.index("AttributeBegin  # Screen"):]
    corners = mesh_points(block)[:4]
    centre = corners.mean(axis=0)
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    eye = centre + normal * 0.9 + np.array([0, 0.05, 0])
    look = " ".join(f"{v:.6g}" for v in (*eye, *centre, 0, 1, 0))
    copy = with_scales(scene, scene.parent / f"_test_{tmp_path.name}.pbrt", "Fill light")
    try:
        copy.write_text(re.sub(r"^LookAt .*$", "LookAt " + look, copy.read_text(), count=1, flags=re.M))
        img = render(pbrt, copy, tmp_path / "p.exr", res=(64, 48), spp=256)
    finally:
        copy.unlink()
    cols = img.sum(axis=0)                       # (w, 3): each column's XYZ
    Y = cols[:, 1]
    band = np.flatnonzero(Y > 0.05 * Y.max())
    assert len(band) >= 6, f"no band: column luminance {np.round(Y, 2)}"
    band = np.arange(band[0], band[-1] + 1)
    mid = len(band) // 2
    a, b = chromaticity(cols[band[:mid]].sum(axis=0)), chromaticity(cols[band[mid:]].sum(axis=0))
    print("band columns", band, "halves xy", a, b)
    assert abs(a[0] - b[0]) > 0.15, (a, b)
    blue, red = (a, b) if a[0] < b[0] else (b, a)
    assert 1 - blue.sum() > 1 - red.sum() + 0.15, (blue, red)   # z = 1 - x - y


def test_tinted_glass_panes_have_their_filter_colours(pbrt, tmp_path):
    """The panes facing the camera: green (x < 0.33, y > 0.5) and amber (x > 0.5); measured
    green (0.26, 0.64), amber (0.59, 0.40) under the flat placeholder lamp."""
    img = render(pbrt, SCENES_DIR / "tinted-glass" / "scene.pbrt", tmp_path / "t.exr", res=(64, 48), spp=32)
    green = chromaticity(img[region_mask(img.shape[:2], (0.46, 0.56, 0.45, 0.62))].sum(axis=0))
    amber = chromaticity(img[region_mask(img.shape[:2], (0.38, 0.42, 0.45, 0.62))].sum(axis=0))
    print("green", green, "amber", amber)
    assert green[0] < 0.33 and green[1] > 0.5, green
    assert amber[0] > 0.5, amber


# ---------------------------------------------------------------------------------------
# The water body for ../shared's glass of water.

def read_ply(path: Path):
    """(vertices (n, 6): x y z nx ny nz, faces (m, 3)) of an ascii or binary little-endian PLY
    with float vertex properties and triangle faces (uchar count, int indices)."""
    data = path.read_bytes()
    end = data.index(b"end_header") + len(b"end_header")
    end += 2 if data[end:end + 2] == b"\r\n" else 1
    header = data[:end].decode().split("\n")
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in header if l.startswith("element face")).split()[2])
    vprops = []
    for l in header:
        if l.startswith("element face"):
            break
        if l.startswith("property float"):
            vprops.append(l.split()[2])
    if "format ascii" in header[1]:
        lines = data[end:].decode().split("\n")
        V = np.array([[float(x) for x in l.split()] for l in lines[:nv]])
        F = np.array([[int(x) for x in l.split()[1:]] for l in lines[nv:nv + nf]])
        return V, F, vprops
    V = np.frombuffer(data[end:end + 4 * nv * len(vprops)], "<f4").reshape(nv, len(vprops)).astype(float)
    rec = np.dtype([("n", "u1"), ("i", "<i4", 3)])
    F = np.frombuffer(data[end + 4 * nv * len(vprops):], rec, count=nf)
    assert np.all(F["n"] == 3)
    return V, F["i"].astype(int), vprops


WATER = SCENES_DIR / "glass-of-water-water" / "water.ply"


def test_water_mesh_is_closed_and_faces_out():
    V, F, props = read_ply(WATER)
    assert props == ["x", "y", "z", "nx", "ny", "nz"]
    P = V[:, :3]
    # Closed: with vertices welded by position, every directed edge has exactly one
    # opposite (the surface's crease repeats positions with other normals).
    key = {tuple(p): i for i, p in enumerate(map(tuple, P))}
    weld = np.array([key[tuple(p)] for p in map(tuple, P)])
    edges = Counter()
    for t in weld[F]:
        for i in range(3):
            edges[(t[i], t[(i + 1) % 3])] += 1
    assert all(n == 1 and edges.get((b, a)) == 1 for (a, b), n in edges.items())
    # Faces out: positive enclosed volume, and each face's normal agrees with its vertices'.
    a, b, c = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6
    assert volume > 20, volume    # about 24 cubic units
    fn = np.cross(b - a, c - a)
    vn = V[F[:, 0], 3:] + V[F[:, 1], 3:] + V[F[:, 2], 3:]
    assert np.all(np.einsum("ij,ij->i", fn, vn) > 0)
    assert np.allclose(np.linalg.norm(V[:, 3:], axis=1), 1, atol=1e-3)


def test_water_fits_inside_the_shared_glass(shared):
    """Every water vertex lies inside the glass's cavity, at least 0.005 from it (the glass's
    facets lie up to 0.001 inside its vertices), and below the rim (y 5.41)."""
    glass_ply = shared / "scenes" / "glass-of-water" / "models" / "Mesh013.ply"
    if not glass_ply.is_file():
        pytest.skip(f"{glass_ply} is absent")
    G, _, props = read_ply(glass_ply)
    gp, gn = G[:, :3], G[:, 3:6]
    gr, gy = np.hypot(gp[:, 0], gp[:, 2]), gp[:, 1]
    radial = np.stack([gp[:, 0], np.zeros(len(gp)), gp[:, 2]], 1) / np.maximum(gr, 1e-9)[:, None]
    towards_axis = np.einsum("ij,ij->i", gn, radial) < -0.05
    inner = (towards_axis | ((gn[:, 1] > 0.5) & (gy > 0.2))) & (gy < 5.38)
    rim = gy.max()
    W, _, _ = read_ply(WATER)
    wr, wy = np.hypot(W[:, 0], W[:, 2]), W[:, 1]
    assert wy.max() < rim - 0.5
    # In the (radius, height) half-plane: each water vertex's nearest inner glass vertex, and
    # the water vertex's signed distance from the glass's tangent there (its normal points
    # into the cavity).
    from scipy.spatial import cKDTree

    g2 = np.c_[gr[inner], gy[inner]]
    n2 = np.c_[np.einsum("ij,ij->i", gn, radial)[inner], gn[inner, 1]]
    n2 /= np.linalg.norm(n2, axis=1)[:, None]
    _, nearest = cKDTree(g2).query(np.c_[wr, wy])
    signed = np.einsum("ij,ij->i", np.c_[wr, wy] - g2[nearest], n2[nearest])
    assert signed.min() > 0.005, (signed.min(), wr[signed.argmin()], wy[signed.argmin()])


def test_glass_of_water_copy_has_the_water_and_renders(pbrt, shared, tmp_path):
    from wavelength_pdf.evaluation.glass_of_water import with_water
    from wavelength_pdf.spectra import SpectrumError

    scene = shared / "scenes" / "glass-of-water" / "scene-v4.pbrt"
    if not scene.is_file():
        pytest.skip(f"{scene} is absent")
    out = with_water(scene, tmp_path / "gow" / "scene.pbrt", resolution=(16, 9), maxdepth=8)
    text = out.read_text()
    assert re.search(r'NamedMaterial "WaterAir"\s+Shape "plymesh" "string filename" \[ "[^"]+water\.ply" \]', text)
    cmd = [str(pbrt), "--quiet", "--spp", "4", "--outfile", str(tmp_path / "g.exr"), str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert np.all(np.isfinite(read_rgb(tmp_path / "g.exr")))
    # Not the glass-of-water scene, or one with its water already in place: refused.
    with pytest.raises(SpectrumError, match="WaterAir"):
        with_water(SCENES_DIR / "colorchecker" / "scene.pbrt", tmp_path / "x.pbrt")
    (tmp_path / "w.pbrt").write_text(scene.read_text().replace('# Shape "plymesh"\n#     "string filename" [ "models/Mesh000.ply" ]',
                                                               'Shape "plymesh" "string filename" [ "models/Mesh000.ply" ]'))
    with pytest.raises(SpectrumError, match="already"):
        with_water(tmp_path / "w.pbrt", tmp_path / "y.pbrt")
