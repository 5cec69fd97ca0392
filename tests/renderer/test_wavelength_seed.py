"""``pbrt --wavelength-seed S`` (design §5.2): each sample's wavelength number drawn from a
hash of the pixel, the sample index and S, every other number of the path unchanged.

- one --seed and two S: the same paths at other wavelengths. With the wavelength noise averaged
  away (``--wavelength-repeats``) the two images agree far more closely than two --seed values
  do; without it they differ;
- the same expectation as the plain render;
- the image records S; a bad S is refused before rendering, with no file written.
"""
from __future__ import annotations

import subprocess

import numpy as np
import pytest

from test_wavelength_repeats import lit_mask, render, scene  # noqa: F401  (the fixture)


def test_one_seed_and_two_wavelength_seeds_trace_the_same_paths(pbrt, scene, tmp_path):  # noqa: F811
    def img(seed, ws, *args):
        return render(pbrt, scene, tmp_path / f"s{seed}w{ws}{len(args)}.exr", "--wavelength-seed", str(ws),
                      *args, spp=1, seed=seed)

    (a, ha), (b, _) = img(1, 1), img(1, 2)
    assert ha["wavelengthSeed"] == "1"
    assert np.mean((a - b) ** 2) > 0  # other wavelengths
    rep = ("--wavelength-repeats", "256")
    base = img(1, 1, *rep)[0]
    m = lit_mask(base)
    same_paths = np.mean((base - img(1, 2, *rep)[0])[m] ** 2)
    other_paths = np.mean((base - img(2, 1, *rep)[0])[m] ** 2)
    assert same_paths < other_paths / 50, (same_paths, other_paths)


def test_a_wavelength_seed_keeps_the_expectation(pbrt, scene, tmp_path):  # noqa: F811
    ref = render(pbrt, scene, tmp_path / "ref.exr", spp=2048, seed=9)[0]
    m = lit_mask(ref)
    got = [render(pbrt, scene, tmp_path / f"w{s}.exr", "--wavelength-seed", str(s), spp=64, seed=s)[0][m]
           for s in (1, 2)]
    n = ref[m].shape[0]
    var = np.mean((got[0] - got[1]) ** 2, axis=0) / 2  # one render's variance per pixel
    se = np.sqrt(var / 2 / n + var * 64 / 2048 / n)  # the mean of two renders, and the reference
    diff = (got[0] + got[1]).mean(axis=0) / 2 - ref[m].mean(axis=0)
    assert np.all(np.abs(diff) < 5 * se), (diff, se)


@pytest.mark.parametrize("value", ["-1", "x", ""])
def test_bad_wavelength_seeds_are_refused(pbrt, scene, tmp_path, value):  # noqa: F811
    out = tmp_path / "bad.exr"
    r = subprocess.run([str(pbrt), "--wavelength-seed", value, "--outfile", str(out), str(scene)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and "--wavelength-seed" in r.stderr
    assert not out.exists()
