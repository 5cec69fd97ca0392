"""Writes the project's two-lamp test scene and its high-pressure sodium spectrum (CC0).

- ``spectra/high-pressure-sodium.spd``: a synthetic high-pressure sodium lamp (formula in
  spectra/README.md), every 0.5 nm over 360-830 nm.
- ``scenes/cornell-box-two-lamps/scene.pbrt``: the project's Cornell box with its one
  ceiling light replaced by two: the tri-band fluorescent lamp on the left, the sodium lamp
  on the right (same size, same scale: both 16 nits).

Run from the repository root: ``python scripts/make_two_lamp_scene.py``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def hps(lam: np.ndarray) -> np.ndarray:
    g = lambda mu, s: np.exp(-((lam - mu) ** 2) / (2 * s * s))  # noqa: E731
    # Pressure-broadened sodium D emission, self-reversed at its centre, on a weak continuum,
    # with the sodium lines at 498.3, 568.8, 615.4 and 819.5 nm.
    broad = g(589.0, 14.0) - 0.85 * g(589.0, 2.5)
    lines = 0.12 * g(498.3, 1.5) + 0.45 * g(568.8, 1.5) + 0.35 * g(615.4, 1.5) + 0.5 * g(819.5, 2.0)
    return np.maximum(0.01 + broad + lines, 0.0)


def main() -> None:
    lam = np.arange(360.0, 830.0 + 1e-9, 0.5)
    spd = ROOT / "spectra" / "high-pressure-sodium.spd"
    spd.write_text("# Synthetic high-pressure sodium lamp (scripts/make_two_lamp_scene.py; CC0)\n" +
                   "".join(f"{l:g} {v:.6g}\n" for l, v in zip(lam, hps(lam))))
    src = (ROOT / "scenes" / "cornell-box" / "scene.pbrt").read_text()
    start = src.index("AttributeBegin  # Light")
    end = src.index("AttributeEnd", start) + len("AttributeEnd")

    def light(name: str, spectrum: str, x0: float, x1: float) -> str:
        return (f"AttributeBegin  # {name}: emits downwards\n"
                f"AreaLightSource \"diffuse\"\n"
                f"    \"spectrum L\" \"../../spectra/{spectrum}\"\n"
                f"    \"float scale\" [ 16 ]\n"
                f"Material \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n"
                f"Shape \"trianglemesh\"\n"
                f"    \"point3 P\" [ {x0} 1.98 -0.22 {x1} 1.98 -0.22 {x1} 1.98 0.16 {x0} 1.98 0.16 ]\n"
                f"    \"integer indices\" [ 0 1 2 0 2 3 ]\n"
                f"AttributeEnd")
    lights = (light("Left light: tri-band fluorescent", "tri-band-fluorescent.spd", -0.5, -0.1) + "\n\n" +
              light("Right light: high-pressure sodium", "high-pressure-sodium.spd", 0.1, 0.5))
    header = ("# The project's Cornell box with two ceiling lights: a tri-band fluorescent lamp (left)\n"
              "# and a high-pressure sodium lamp (right); written by scripts/make_two_lamp_scene.py (CC0).\n")
    body = src[:start] + lights + src[end:]
    body = "\n".join(l for l in body.splitlines()[2:]) + "\n"  # drop the one-light header lines
    out = ROOT / "scenes" / "cornell-box-two-lamps" / "scene.pbrt"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(header + body)


if __name__ == "__main__":
    main()
