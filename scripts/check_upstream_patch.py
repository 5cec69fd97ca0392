#!/usr/bin/env python3
"""The image checks of the wavelength-pdf patch for upstream pbrt-v4 (run by
``scripts/check_upstream_patch.sh``, which builds the two binaries first).

On the six evaluation scenes (``../shared/scenes``, lit by the compact fluorescent lamp LSPDD
2482 cut to 380..780 nm, shrunk to at most ``--size`` pixels a side) and on a dispersive
scene (the Cornell box with a glass sphere of spectral index ``glass-F11``):

(a) without ``--wavelength-pdf`` the patched binary's pixels equal unpatched upstream's bit
    for bit (same seed), with the CPU integrators and with ``--wavefront``;
(b) with the table, the image means equal upstream's own (visible sampling) within noise:
    z = difference / standard error, the standard error pooled from the per-pixel spread over
    ``--seeds`` seeds; |z| < 4 on every channel passes;
(c) the mean CIEDE2000 against a high-spp truth (the patched binary with the table, a seed of
    its own) is lower with the table than with upstream's visible sampling at equal spp;
(d) (b) and (c) with ``--wavefront`` (against the same CPU truth: path, volpath and bdpt
    share one expectation);
(e) the dispersive scene stays unbiased ((b) on it);
(f) ``--wavelength-sampling emission`` (a table built from the scene's own lamps, design §1.7)
    converges to upstream's image too, CPU and ``--wavefront`` ((b) with it; its CIEDE2000 is
    reported beside the table's);
(g) bad lights with emission sampling (a blackbody of 0 K, lights of zero power) stop the
    patched binary before rendering with ``FILE:LINE:COL: reason`` and exit status 1.
Then the acceptance figure: on the Cornell box under 2482 at 256 spp, the error ratio
uniform / table for patched upstream (upstream's uniform sampling is its "spectral" film on
380..780 nm, four stratified wavelengths) and for this repository's ``pbrt``.

Renders are cached under ``WORK/renders`` by binary, scene and arguments, so a second run
only renders what changed. Prints a table of every figure; exit status 1 if a check fails.
"""
from __future__ import annotations

import argparse
import hashlib
import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "python"))

from wavelength_pdf.evaluation.metrics import delta_e_map  # noqa: E402
from wavelength_pdf.evaluation.scene_edit import edit_scene  # noqa: E402
from wavelength_pdf.exr import read_rgb  # noqa: E402
from wavelength_pdf.spectra import load_spectrum  # noqa: E402

SCENES = ("cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase", "glass-of-water")
DISPERSIVE = "cornell-dispersive"
#: |z| below this passes (b): about 6e-5 two-sided for one normal deviate.
Z_LIMIT = 4.0
LAMP = "2482"  # LSPDD 2482, a compact fluorescent lamp (the acceptance figure's lamp)

# A glass sphere with a wavelength-dependent index (pbrt-v4's named Schott F11 glass) in the
# Cornell box (floor y = 0, walls at x, z = +-1, light at y = 1.98).
_GLASS_SPHERE = """
AttributeBegin
    Material "dielectric" "spectrum eta" "glass-F11"
    Translate -0.3 1.05 0.35
    Shape "sphere" "float radius" 0.33
AttributeEnd
"""


class CheckError(RuntimeError):
    """A render failed or an input is missing (the message says which)."""


@dataclass
class Renderer:
    name: str
    binary: Path
    digest: str

    @staticmethod
    def of(name: str, binary: Path) -> "Renderer":
        if not binary.is_file():
            raise CheckError(f"{binary}: no such binary")
        return Renderer(name, binary, hashlib.sha1(binary.read_bytes()).hexdigest()[:16])


class Cache:
    """Renders by (binary, scene text, arguments) under one folder."""

    def __init__(self, folder: Path, nthreads: int):
        self.folder = folder
        self.nthreads = nthreads
        folder.mkdir(parents=True, exist_ok=True)
        self.rendered = 0
        self.seconds = 0.0

    def render(self, r: Renderer, scene: Path, args: list[str]) -> np.ndarray:
        key = hashlib.sha1("\0".join([r.digest, scene.read_text(), *args]).encode()).hexdigest()[:20]
        out = self.folder / f"{scene.parent.name}-{r.name}-{key}.exr"
        if not out.exists():
            tmp = out.with_name(out.stem + ".tmp.exr")
            cmd = [str(r.binary), "--quiet", "--nthreads", str(self.nthreads), *args,
                   "--outfile", str(tmp), str(scene)]
            t0 = time.time()
            proc = subprocess.run(cmd, capture_output=True, text=True)
            self.seconds += time.time() - t0
            if proc.returncode != 0 or not tmp.exists():
                raise CheckError(f"render failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stderr[-2000:]}")
            tmp.replace(out)
            self.rendered += 1
        return read_rgb(out)


def prepare_scenes(shared: Path, work: Path, size: int) -> dict[str, Path]:
    """The scenes lit by the lamp, at most ``size`` pixels a side, and the dispersive one."""
    lamp = load_spectrum(str(shared / "spectra" / "lspdd" / f"{LAMP}.csv"), lo=380.0, hi=780.0)
    out = {}
    for name in SCENES:
        src = shared / "scenes" / name / "scene-v4.pbrt"
        if not src.is_file():
            raise CheckError(f"{src}: scene not found")
        text = src.read_text()
        xs = re.search(r'"integer xresolution"\s*\[\s*(\d+)', text)
        ys = re.search(r'"integer yresolution"\s*\[\s*(\d+)', text)
        w, h = (int(xs[1]) if xs else 1280), (int(ys[1]) if ys else 720)
        out[name] = edit_scene(src, lamp, work / "scenes" / name / "scene.pbrt",
                               resolution=size / max(w, h))
    disp = work / "scenes" / DISPERSIVE / "scene.pbrt"
    disp.parent.mkdir(parents=True, exist_ok=True)
    text = out["cornell-box"].read_text() + _GLASS_SPHERE
    if not disp.exists() or disp.read_text() != text:
        disp.write_text(text)
    out[DISPERSIVE] = disp
    return out


def spectral_film_copy(scene: Path) -> Path:
    """The scene with upstream's "spectral" film on 380..780 nm (stratified uniform sampling)."""
    text = scene.read_text()
    new, n = re.subn(r'Film\s+"rgb"', 'Film "spectral" "float lambdamin" [ 380 ] "float lambdamax" [ 780 ]', text)
    if n != 1:
        raise CheckError(f"{scene}: expected one Film \"rgb\" statement")
    out = scene.with_name("scene-spectral.pbrt")
    if not out.exists() or out.read_text() != new:
        out.write_text(new)
    return out


def pooled_mean(images: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel image mean over seeds and its standard error (pooled per-pixel variance)."""
    stack = np.stack(images)  # (k, h, w, 3)
    k, npix = stack.shape[0], stack.shape[1] * stack.shape[2]
    mean = stack.mean(axis=(0, 1, 2))
    var_pixel = stack.var(axis=0, ddof=1)  # (h, w, 3)
    se = np.sqrt(var_pixel.sum(axis=(0, 1)) / k) / npix
    return mean, se


def precision(mean: np.ndarray, se_a: np.ndarray, se_b: np.ndarray) -> str:
    """The standard error of a difference of image means, in % of the mean, per channel."""
    return " ".join(f"{100 * np.sqrt(a * a + b * b) / abs(m):.2g}" for m, a, b in zip(mean, se_a, se_b))


def mean_delta_e(images: list[np.ndarray], truth: np.ndarray) -> tuple[float, float]:
    """Mean CIEDE2000 against the truth, averaged over seeds, and its standard error."""
    e = np.array([float(delta_e_map(img, truth).mean()) for img in images])
    return float(e.mean()), float(e.std(ddof=1) / np.sqrt(len(e))) if len(e) > 1 else 0.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--unpatched", type=Path, required=True, help="unpatched upstream pbrt")
    ap.add_argument("--patched", type=Path, required=True, help="patched upstream pbrt")
    ap.add_argument("--repo-pbrt", type=Path, default=ROOT / "build" / "pbrt", help="this repository's pbrt")
    ap.add_argument("--table", type=Path, required=True, help="the wavelength table for LSPDD 2482")
    ap.add_argument("--shared", type=Path, default=ROOT.parent / "shared")
    ap.add_argument("--work", type=Path, required=True, help="folder for scenes and renders")
    ap.add_argument("--size", type=int, default=32, help="longest image side in pixels (default 32)")
    ap.add_argument("--spp", type=int, default=32, help="spp of the (b), (c) renders (default 32)")
    ap.add_argument("--seeds", type=int, default=4, help="seeds per method for (b), (c) (default 4)")
    ap.add_argument("--truth-spp", type=int, default=1024, help="spp of the truths (default 1024)")
    ap.add_argument("--ratio-size", type=int, default=64, help="Cornell box side for the ratio (default 64)")
    ap.add_argument("--ratio-spp", type=int, default=256)
    ap.add_argument("--ratio-truth-spp", type=int, default=4096)
    ap.add_argument("--nthreads", type=int, default=2)
    args = ap.parse_args()

    t_start = time.time()
    up = Renderer.of("upstream", args.unpatched)
    pa = Renderer.of("patched", args.patched)
    cache = Cache(args.work / "renders", args.nthreads)
    scenes = prepare_scenes(args.shared, args.work, args.size)
    table = ["--wavelength-pdf", str(args.table.resolve())]
    failures: list[str] = []
    rows: list[str] = []

    def say(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    # (a) bit for bit without the flag.
    rows.append("| scene | (a) CPU pixels equal | (a) --wavefront pixels equal |")
    rows.append("|---|---|---|")
    for name, scene in scenes.items():
        cells = []
        for mode in ([], ["--wavefront"]):
            a = cache.render(up, scene, ["--spp", "4", "--seed", "7", *mode])
            b = cache.render(pa, scene, ["--spp", "4", "--seed", "7", *mode])
            same = a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))
            differing = int(np.sum(np.any(a != b, axis=-1))) if a.shape == b.shape else -1
            cells.append(f"{'yes' if same else 'NO'} ({a.shape[1]}x{a.shape[0]}, {differing} differ)")
            if not same:
                failures.append(f"(a) {name} {' '.join(mode) or 'CPU'}: {differing} pixels differ")
        rows.append(f"| {name} | {cells[0]} | {cells[1]} |")
        say(f"(a) {name}: {cells}")

    # (b)-(f): seeds of visible (unpatched), table and emission (patched), CPU and wavefront.
    emission = ["--wavelength-sampling", "emission"]
    res_rows = ["| scene | mode | mean RGB upstream | mean RGB table | SE of the difference, % (R G B) | max abs z "
                "| ΔE visible | ΔE table | visible/table | (f) max abs z emission | ΔE emission |",
                "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, scene in scenes.items():
        truth = cache.render(pa, scene, ["--spp", str(args.truth_spp), "--seed", "100000", *table])
        for mode in ([], ["--wavefront"]):
            label = "wavefront" if mode else "CPU"
            vis = [cache.render(up, scene, ["--spp", str(args.spp), "--seed", str(s), *mode])
                   for s in range(1, args.seeds + 1)]
            tab = [cache.render(pa, scene, ["--spp", str(args.spp), "--seed", str(s), *mode, *table])
                   for s in range(1, args.seeds + 1)]
            mv, sv = pooled_mean(vis)
            mt, st = pooled_mean(tab)
            z = (mt - mv) / np.sqrt(sv ** 2 + st ** 2)
            zmax = float(np.max(np.abs(z)))
            ev, _ = mean_delta_e(vis, truth)
            et, _ = mean_delta_e(tab, truth)
            emi = [cache.render(pa, scene, ["--spp", str(args.spp), "--seed", str(s), *mode, *emission])
                   for s in range(1, args.seeds + 1)]
            me, se_ = pooled_mean(emi)
            zemax = float(np.max(np.abs((me - mv) / np.sqrt(sv ** 2 + se_ ** 2))))
            ee, _ = mean_delta_e(emi, truth)
            tag = "(e)" if name == DISPERSIVE else ("(b)" if not mode else "(d)")
            if not zmax < Z_LIMIT:
                failures.append(f"{tag} {name} {label}: image means differ, max |z| = {zmax:.2f}")
            if not zemax < Z_LIMIT:
                failures.append(f"(f) {name} {label}: emission sampling's image mean differs, max |z| = {zemax:.2f}")
            if name != DISPERSIVE and not et < ev:
                failures.append(f"(c) {name} {label}: ΔE table {et:.3f} not below visible {ev:.3f}")
            fmt = lambda m: " ".join(f"{x:.4g}" for x in m)  # noqa: E731
            res_rows.append(f"| {name} | {label} | {fmt(mv)} | {fmt(mt)} | {precision(mv, sv, st)} | {zmax:.2f} | "
                            f"{ev:.3f} | {et:.3f} | {ev / et:.2f} | {zemax:.2f} | {ee:.3f} |")
            say(f"(b-f) {name} {label}: z {zmax:.2f} (emission {zemax:.2f}), ΔE {ev:.3f} vs {et:.3f} "
                f"(emission {ee:.3f})")

    # (g) bad lights with emission sampling: an error naming the light, before rendering.
    bad_rows = ["| (g) bad light | exit status | message |", "|---|---|---|"]
    head = scenes["cornell-box"].read_text().split("WorldBegin")[0] + "WorldBegin\n"
    for label, world, want in (
            ("blackbody of 0 K", 'AttributeBegin\nAreaLightSource "diffuse" "blackbody L" [0]\n'
                                 'Shape "sphere"\nAttributeEnd\n', "emitted power is"),
            ("zero power", 'LightSource "point" "float scale" [0]\n', "emits between 360 and 830 nm")):
        bad = args.work / "scenes" / "bad" / f"{label.split()[0]}.pbrt"
        bad.parent.mkdir(parents=True, exist_ok=True)
        bad.write_text(head + world)
        line = head.count("\n") + (2 if world.startswith("AttributeBegin") else 1)
        proc = subprocess.run([str(pa.binary), "--quiet", *emission, "--outfile", str(bad.with_suffix(".exr")),
                               str(bad)], capture_output=True, text=True)
        msg = (proc.stderr.strip().splitlines() or [""])[-1]
        ok = proc.returncode == 1 and f"{bad}:{line}:" in msg and want in msg and not bad.with_suffix(".exr").exists()
        bad_rows.append(f"| {label} | {proc.returncode} | {msg[:160]} |")
        if not ok:
            failures.append(f"(g) {label}: expected exit 1 naming {bad}:{line}, got {proc.returncode}: {msg}")
        say(f"(g) {label}: {proc.returncode} {msg}")

    # The acceptance figure: uniform / table at 256 spp, Cornell box under 2482.
    lamp = load_spectrum(str(args.shared / "spectra" / "lspdd" / f"{LAMP}.csv"), lo=380.0, hi=780.0)
    cb = edit_scene(args.shared / "scenes" / "cornell-box" / "scene-v4.pbrt", lamp,
                    args.work / "scenes" / "cornell-ratio" / "scene.pbrt",
                    resolution=(args.ratio_size, args.ratio_size))
    cb_spectral = spectral_film_copy(cb)
    seeds = range(1, 4)
    ratio_rows = ["| renderer | ΔE uniform | ΔE visible | ΔE table | ΔE emission | uniform/table | visible/table "
                  "| visible/emission |",
                  "|---|---|---|---|---|---|---|---|"]
    spp = ["--spp", str(args.ratio_spp)]
    truth = cache.render(pa, cb, ["--spp", str(args.ratio_truth_spp), "--seed", "100000", *table])
    uni = [cache.render(up, cb_spectral, [*spp, "--seed", str(s)]) for s in seeds]
    vis = [cache.render(up, cb, [*spp, "--seed", str(s)]) for s in seeds]
    tab = [cache.render(pa, cb, [*spp, "--seed", str(s), *table]) for s in seeds]
    emi = [cache.render(pa, cb, [*spp, "--seed", str(s), *emission]) for s in seeds]
    (eu, su), (ev, sv), (et, st), (ee, se_) = (mean_delta_e(x, truth) for x in (uni, vis, tab, emi))
    up_ratio = eu / et
    # (b) once more, with 32 times the samples per pixel of the scene rows above.
    (mu, seu), (mv, sev), (mt, set_), (me, see) = (pooled_mean(x) for x in (uni, vis, tab, emi))
    z_rows = ["| upstream sampler | mean RGB upstream | mean RGB table | SE of the difference, % (R G B) | max abs z |",
              "|---|---|---|---|---|"]
    for label, m, se, mp, sp_ in (("uniform (spectral film)", mu, seu, mt, set_), ("visible", mv, sev, mt, set_),
                                  ("visible, against emission", mv, sev, me, see)):
        zmax = float(np.max(np.abs((mp - m) / np.sqrt(se ** 2 + sp_ ** 2))))
        z_rows.append(f"| {label} | {' '.join(f'{x:.4g}' for x in m)} | {' '.join(f'{x:.4g}' for x in mp)} | "
                      f"{precision(m, se, sp_)} | {zmax:.2f} |")
        if not zmax < Z_LIMIT:
            failures.append(f"(b) cornell-ratio {label}: image means differ, max |z| = {zmax:.2f}")
    ratio_rows.append(f"| patched upstream pbrt-v4 | {eu:.3f} ± {su:.3f} | {ev:.3f} ± {sv:.3f} | "
                      f"{et:.3f} ± {st:.3f} | {ee:.3f} ± {se_:.3f} | {eu / et:.2f} | {ev / et:.2f} | "
                      f"{ev / ee:.2f} |")
    repo_ratio = None
    if args.repo_pbrt.is_file():
        rp = Renderer.of("repo", args.repo_pbrt)
        rtruth = cache.render(rp, cb, ["--spp", str(args.ratio_truth_spp), "--seed", "100000", *table])
        runi = [cache.render(rp, cb, [*spp, "--seed", str(s), "--wavelength-sampling", "uniform",
                                      "--wavelength-range", "380", "780"]) for s in seeds]
        rvis = [cache.render(rp, cb, [*spp, "--seed", str(s)]) for s in seeds]
        rtab = [cache.render(rp, cb, [*spp, "--seed", str(s), *table]) for s in seeds]
        remi = [cache.render(rp, cb, [*spp, "--seed", str(s), *emission]) for s in seeds]
        (ru, rsu), (rv, rsv), (rt, rst), (re_, rse) = (mean_delta_e(x, rtruth) for x in (runi, rvis, rtab, remi))
        repo_ratio = ru / rt
        ratio_rows.append(f"| this repository's pbrt | {ru:.3f} ± {rsu:.3f} | {rv:.3f} ± {rsv:.3f} | "
                          f"{rt:.3f} ± {rst:.3f} | {re_:.3f} ± {rse:.3f} | {ru / rt:.2f} | {rv / rt:.2f} | "
                          f"{rv / re_:.2f} |")
        if not up_ratio >= repo_ratio:
            failures.append(f"ratio: patched upstream's uniform/table {up_ratio:.2f} below this "
                            f"repository's {repo_ratio:.2f}")
    else:
        print(f"note: {args.repo_pbrt} not found; the repository's ratio is not measured", file=sys.stderr)

    print(f"\nwavelength-pdf patch check: {len(scenes)} scenes at most {args.size} px a side, lamp LSPDD "
          f"{LAMP} (380..780 nm), table {args.table.name}")
    print("\n".join(rows))
    print(f"\n(b)-(f): {args.seeds} seeds x {args.spp} spp per method; truth: patched + table, "
          f"{args.truth_spp} spp; |z| < {Z_LIMIT:g} passes")
    print("\n".join(res_rows))
    print("\n" + "\n".join(bad_rows))
    print(f"\nCornell box under LSPDD {LAMP}, {args.ratio_size}x{args.ratio_size}, {args.ratio_spp} spp, "
          f"3 seeds, truth {args.ratio_truth_spp} spp with the table (each renderer its own)")
    print("\n".join(ratio_rows))
    print(f"\n(b) on the same renders (3 seeds x {args.ratio_spp} spp, CPU): patched upstream's table against "
          "unpatched upstream's samplers")
    print("\n".join(z_rows))
    print(f"\n{cache.rendered} renders in {cache.seconds:.0f} s; {time.time() - t_start:.0f} s in all")
    if failures:
        print("\nFAILED:\n  " + "\n  ".join(failures))
        return 1
    print("\nall checks passed")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except CheckError as e:
        print(f"check_upstream_patch: {e}", file=sys.stderr)
        sys.exit(2)
