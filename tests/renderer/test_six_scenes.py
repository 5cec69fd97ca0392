"""Speed work keeps the picture: the six evaluation scenes render as they did.

``tests/data/six-scenes-reference.json`` holds, for each scene of ``../shared/scenes``, the
8x8-pixel block means of a 64x64 render (maximum depth 5, as ``scripts/bench_renderer.py``
measures them) over 16 seeds, and the seed-to-seed standard deviation of each block, made
with the renderer before the changes of docs/performance.md ("Images kept"). The test renders
the same scenes with 4 other seeds and compares, per channel, the blocks' deviations from the
reference in units of the noise the reference measured (their sum, so that a few outlying
blocks from rare bright paths do not decide it) and the image mean within 4.5 standard errors.

Regenerate the reference (only when the picture is meant to change, with a reason in the
commit) with ``python tests/renderer/test_six_scenes.py --write [PBRT]``.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from repo_paths import PBRT, REPO, SHARED  # noqa: E402

sys.path.insert(0, str(REPO / "python"))
from wavelength_pdf.evaluation.scene_edit import edit_scene  # noqa: E402
from wavelength_pdf.exr import read_rgb  # noqa: E402

SCENES = ("cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase", "glass-of-water")
REFERENCE = REPO / "tests" / "data" / "six-scenes-reference.json"
SIZE, BLOCK, SPP, MAXDEPTH = 64, 8, 64, 5
REFERENCE_SEEDS = range(1, 17)
TEST_SEEDS = range(101, 105)


def small_copy(scene: Path, out: Path) -> Path:
    """``scene`` at SIZE x SIZE pixels and maximum depth MAXDEPTH."""
    return edit_scene(scene, None, out, resolution=(SIZE, SIZE), maxdepth=MAXDEPTH)


def block_means(binary: Path, scene: Path, seeds, tmp: Path) -> np.ndarray:
    """(len(seeds), 3, SIZE/BLOCK, SIZE/BLOCK) block means of renders at SPP spp."""
    out = []
    for seed in seeds:
        exr = tmp / f"s{seed}.exr"
        cmd = [str(binary), "--quiet", "--spp", str(SPP), "--seed", str(seed), "--outfile", str(exr), str(scene)]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        assert proc.returncode == 0, f"{' '.join(cmd)} failed:\n{proc.stderr}"
        img = read_rgb(exr)  # (h, w, 3)
        nb = SIZE // BLOCK
        out.append(img.reshape(nb, BLOCK, nb, BLOCK, 3).mean(axis=(1, 3)).transpose(2, 0, 1))
    return np.array(out, dtype=np.float64)


def _scene_path(name: str) -> Path:
    return SHARED / "scenes" / name / "scene-v4.pbrt"


@pytest.fixture(scope="module")
def reference() -> dict:
    assert REFERENCE.is_file(), f"{REFERENCE} is missing"
    return json.loads(REFERENCE.read_text())


@pytest.mark.parametrize("name", SCENES)
def test_scene_renders_as_before(name, reference, pbrt, tmp_path):
    path = _scene_path(name)
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    ref = reference[name]
    mean_ref, sd_ref, n_ref = np.array(ref["mean"]), np.array(ref["sd"]), ref["seeds"]
    scene = small_copy(path, tmp_path / "scene.pbrt")
    blocks = block_means(pbrt, scene, TEST_SEEDS, tmp_path)
    n = len(blocks)
    mean = blocks.mean(axis=0)
    # The reference's seed-to-seed deviation is the noise of one seed (same spp, same
    # sampler); flat blocks (sd 0, e.g. black background) must match to rounding.
    var = sd_ref**2 * (1 / n + 1 / n_ref)
    flat = var == 0
    assert np.allclose(mean[flat], mean_ref[flat], rtol=1e-4, atol=1e-6), f"{name}: flat blocks changed"
    # Per channel, the blocks' z-scores summed: a change of the picture moves many blocks the
    # same way, while the rare bright paths of one seed move one block (a single-block test
    # would need to know the tails of every scene's noise). Under the reference's noise the
    # sum over N blocks divided by sqrt(N) is close to N(0, 1); a 2% change of brightness
    # gives 2.5 to 37 on these scenes.
    for c in range(3):
        ok = ~flat[c]
        z = (mean[c][ok] - mean_ref[c][ok]) / np.sqrt(var[c][ok])
        t = z.sum() / np.sqrt(z.size)
        assert abs(t) < 4, (f"{name}: channel {c} differs from the reference beyond noise (summed z {t:.1f} "
                            f"over {z.size} blocks; worst block z {z[np.argmax(abs(z))]:.1f})")
        # and the image mean, with every block weighing the same
        d = mean[c].mean() - mean_ref[c].mean()
        se = np.sqrt(var[c].sum()) / var[c].size
        assert abs(d) <= 4.5 * se + 1e-6 * abs(mean_ref[c].mean()), \
            f"{name}: channel {c} mean {mean[c].mean():.6g} vs reference {mean_ref[c].mean():.6g} (se {se:.2g})"


def write_reference(binary: Path) -> None:
    data = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in SCENES:
            path = _scene_path(name)
            if not path.is_file():
                raise SystemExit(f"{path} is absent")
            scene = small_copy(path, tmp / f"{name}.pbrt")
            blocks = block_means(binary, scene, REFERENCE_SEEDS, tmp)
            data[name] = {"seeds": len(blocks), "spp": SPP, "size": SIZE, "block": BLOCK,
                          "mean": blocks.mean(axis=0).tolist(), "sd": blocks.std(axis=0, ddof=1).tolist()}
            print(f"{name}: mean {blocks.mean(axis=(0, 2, 3))}", flush=True)
    REFERENCE.write_text(json.dumps(data, indent=None) + "\n")
    print(f"wrote {REFERENCE}")


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] != "--write":
        raise SystemExit(__doc__)
    write_reference(Path(sys.argv[2]) if len(sys.argv) > 2 else PBRT)
