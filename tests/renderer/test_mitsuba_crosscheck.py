"""An independent-renderer check: the same spectral Cornell-box-like scene rendered by
Mitsuba 3 (PyPI, variant scalar_spectral) and by our pbrt, with the same absolute spectral
radiance, agrees per channel in the image mean to 1% (beyond noise).

Both renderers read the same binary PLY quads and the same piecewise-linear spectra. Units:
pbrt-v4 normalizes an emitter to 1 nit and multiplies by "scale", so scale = integral of
ybar * S (1 nm steps, 360-830) gives radiance S(lambda) exactly; pbrt's cie1931 sensor reports
Y = integral ybar * L, while Mitsuba divides by the integral of ybar (an equal-energy spectrum of
radiance 1 shows as XYZ = 1). So Mitsuba's image is
multiplied by that integral (106.856895) before the comparison.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import colour
import numpy as np
import pytest

from wavelength_pdf.exr import read_rgb

mi = pytest.importorskip("mitsuba")

CIE_Y_INTEGRAL = 106.856895  # sum of the CIE 1931 ybar at 1 nm over 360-830 nm
WL = np.arange(360.0, 831.0, 10.0)
YBAR = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]


def smooth(center: float, width: float, lo: float, hi: float) -> np.ndarray:
    """A smooth reflectance between lo and hi: a Gaussian bump of the given centre and width."""
    return lo + (hi - lo) * np.exp(-0.5 * ((WL - center) / width) ** 2)


SPECTRA = {
    "white": np.full_like(WL, 0.75),
    "red": 0.05 + 0.6 / (1.0 + np.exp(-(WL - 590.0) / 12.0)),
    "green": smooth(530.0, 35.0, 0.05, 0.55),
    "light": 1.0 * np.exp(-0.5 * ((WL - 450.0) / 30.0) ** 2) + np.exp(-0.5 * ((WL - 600.0) / 60.0) ** 2) + 0.05,
}


def photometric(values: np.ndarray) -> float:
    """pbrt-v4's normalization constant: sum of ybar * S at integer nm over 360-830."""
    lam = np.arange(360, 831)
    ybar = YBAR.copy().align(colour.SpectralShape(360, 830, 1)).values[:, 1]
    return float(np.sum(ybar * np.interp(lam, WL, values)))


def write_ply(path: Path, quads: list[tuple]) -> None:
    """Binary little-endian PLY of quads (each four corners, counter-clockwise seen from the lit side)."""
    pts = np.array([p for q in quads for p in q], dtype="<f4")
    # Two triangles a quad (Mitsuba reads triangle meshes only).
    faces = [t for i in range(len(quads)) for t in ((4 * i, 4 * i + 1, 4 * i + 2), (4 * i, 4 * i + 2, 4 * i + 3))]
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(pts.tobytes())
        for face in faces:
            f.write(np.uint8(3).tobytes() + np.array(face, dtype="<i4").tobytes())


# The room: x in [-1, 1], y in [0, 2], z in [-1, 1], open towards +z; all faces point inwards.
GEOMETRY = {
    "white": [((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1)),   # floor, +y
              ((-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)),   # ceiling, -y
              ((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1))],  # back, +z
    "red": [((-1, 0, -1), (-1, 2, -1), (-1, 2, 1), (-1, 0, 1))],    # left, +x
    "green": [((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1))],      # right, -x
    "light": [((-0.25, 1.98, -0.25), (0.25, 1.98, -0.25), (0.25, 1.98, 0.25), (-0.25, 1.98, 0.25))],  # -y
}
RES, FOV, MAXDEPTH = 40, 45.0, 4
EYE, TARGET = (0.0, 1.0, 3.6), (0.0, 1.0, 0.0)


def render_mitsuba(tmp: Path, spp: int, seed: int) -> np.ndarray:
    mi.set_variant("scalar_spectral")

    def spec(v):
        return {"type": "irregular", "wavelengths": ",".join(f"{w:g}" for w in WL),
                "values": ",".join(f"{x:.9g}" for x in v)}

    scene = {"type": "scene",
             "integrator": {"type": "path", "max_depth": MAXDEPTH + 1, "rr_depth": 1000},
             "sensor": {"type": "perspective", "fov": FOV, "fov_axis": "smaller",
                        "to_world": mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=[0, 1, 0]),
                        "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"},
                                 "pixel_format": "rgb"},
                        "sampler": {"type": "independent", "sample_count": spp}}}
    for name in GEOMETRY:
        shape = {"type": "ply", "filename": str(tmp / f"{name}.ply"), "face_normals": True}
        if name == "light":
            shape["emitter"] = {"type": "area", "radiance": spec(SPECTRA["light"])}
            shape["bsdf"] = {"type": "diffuse", "reflectance": 0.0}
        else:
            shape["bsdf"] = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": spec(SPECTRA[name])}}
        scene[name] = shape
    return np.asarray(mi.render(mi.load_dict(scene), seed=seed), dtype=np.float64)


def pbrt_scene(tmp: Path, spp: int) -> Path:
    def spec(v):
        return "[ " + " ".join(f"{w:g} {x:.9g}" for w, x in zip(WL, v)) + " ]"

    lines = [f'LookAt {EYE[0]} {EYE[1]} {EYE[2]}  {TARGET[0]} {TARGET[1]} {TARGET[2]}  0 1 0',
             f'Camera "perspective" "float fov" [ {FOV} ]',
             f'Sampler "independent" "integer pixelsamples" [ {spp} ]',
             'PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]',
             f'Integrator "path" "integer maxdepth" [ {MAXDEPTH} ]',
             f'Film "rgb" "integer xresolution" [ {RES} ] "integer yresolution" [ {RES} ] "string filename" [ "pbrt.exr" ]',
             "WorldBegin"]
    for name in GEOMETRY:
        lines.append("AttributeBegin")
        if name == "light":
            lines.append(f'AreaLightSource "diffuse" "spectrum L" {spec(SPECTRA["light"])} '
                         f'"float scale" [ {photometric(SPECTRA["light"]):.9g} ]')
            lines.append('Material "diffuse" "rgb reflectance" [ 0 0 0 ]')
        else:
            lines.append(f'Material "diffuse" "spectrum reflectance" {spec(SPECTRA[name])}')
        lines.append(f'Shape "plymesh" "string filename" [ "{name}.ply" ]')
        lines.append("AttributeEnd")
    path = tmp / "scene.pbrt"
    path.write_text("\n".join(lines) + "\n")
    return path


def mean_and_noise(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Image mean of two independent renders and its standard error, per channel.

    The per-pixel noise variance is half the variance of the difference of the two renders; the
    mean of both has a variance of that over 2 over the pixel count."""
    pixel_var = np.mean((a - b) ** 2, axis=(0, 1)) / 2.0
    return 0.5 * (a + b).mean(axis=(0, 1)), np.sqrt(pixel_var / 2.0 / (a.shape[0] * a.shape[1]))


def test_pbrt_agrees_with_mitsuba(tmp_path: Path, pbrt: Path) -> None:
    for name, quads in GEOMETRY.items():
        write_ply(tmp_path / f"{name}.ply", quads)

    spp = 1024
    scene = pbrt_scene(tmp_path, spp)
    ours = []
    for seed in (7, 8):
        out = tmp_path / f"pbrt-{seed}.exr"
        subprocess.run([str(pbrt), "--quiet", "--seed", str(seed), "--outfile", str(out), str(scene)],
                       check=True, cwd=tmp_path, timeout=300)
        ours.append(read_rgb(out))
    # Mitsuba (scalar, simple scene) is cheap: give it 4x the samples to keep the noise down.
    theirs = [render_mitsuba(tmp_path, 4 * spp, seed) * CIE_Y_INTEGRAL for seed in (1, 2)]
    assert all(np.all(np.isfinite(img)) for img in ours + theirs)

    m_ours, se_ours = mean_and_noise(*ours)
    m_theirs, se_theirs = mean_and_noise(*theirs)
    rel = np.abs(m_ours / m_theirs - 1.0)
    noise = np.sqrt(se_ours**2 + se_theirs**2) / m_theirs
    assert np.all(noise < 0.004), f"too noisy to check 1% agreement: relative noise {noise}"
    assert np.all(rel < 0.01 + 3.0 * noise), f"pbrt {m_ours} vs mitsuba {m_theirs}: rel {rel}, noise {noise}"
