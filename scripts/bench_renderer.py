#!/usr/bin/env python3
"""Renderer benchmark: this repository's ``pbrt`` beside upstream pbrt-v4, in one run.

Renders the six evaluation scenes ``../shared/scenes/<scene>/scene-v4.pbrt`` (cornell-box,
veach-mis, teapot, veach-bidir, staircase, glass-of-water), each as a copy at 256x256 with
maximum depth 5 (upstream pbrt-v4 has no --resolution or --maxdepth flag, so both renderers
read the same edited copy), with this repository's ``build/pbrt`` and with unpatched upstream
pbrt-v4 (the binary ``scripts/check_upstream_patch.sh`` builds), and prints paths per
CPU-second for both and their ratio.

Both are measured the same way, from outside: the CPU time (user + system, from the
process's resource usage) of a render at ``--spp`` and of one at three times as many, so
that scene loading cancels: paths per CPU-second = (extra paths) / (extra CPU seconds), with
paths = pixels x spp. The renderers alternate, ``--reps`` times; the medians are printed.

Scenes written for "bdpt" render with bdpt in upstream and with path in this ``pbrt`` (its
documented difference); those rows say so. With ``--upstream-path`` upstream renders them with
"path" too, so that the ratio compares the same algorithm.

Then the Mitsuba cross-check box: the project's Cornell box (``scenes/cornell-box/scene.pbrt``
and its Mitsuba 3 twin ``scene.xml``: the same room, reflectances, camera and tri-band lamp)
at 256x256 and ``--box-spp`` (default 256), rendered alternately by this ``pbrt`` (2 threads)
and by Mitsuba 3 ``llvm_ad_spectral`` (Dr.Jit's thread pool, one thread per core; the LLVM
library from ``wavelength_pdf.mitsuba.llvm``, i.e. Debian's libllvm19 through
``DRJIT_LIBLLVM_PATH``), each in its own process, whose whole CPU time (user + system:
loading, Mitsuba's kernel compilation and Python start-up included) is what counts, as a
user waiting for the picture would count it. Depth is matched by convention: pbrt's
``maxdepth 5`` counts scattering events, so its longest path has 6 segments including the
camera ray, which is Mitsuba's ``max_depth 6`` (Mitsuba counts segments; 1 is emitters seen
directly). Both keep their default Russian roulette (pbrt-v4's from the second bounce;
Mitsuba's from depth ``rr_depth`` 5), so Mitsuba traces at least as many segments per path.
Mitsuba renders in passes of at most 64 spp from one loaded scene. Skipped (and said so)
when Mitsuba or its LLVM is missing.

With the patched upstream binary (also built by the check script) it then prints what the
table costs there: the Cornell box rendered alternately with visible sampling (upstream's
default) and with ``--wavelength-pdf TABLE``, one thread, the CPU time of the whole process
(loading is the same for both), and the median per-pair ratio table / visible (the target
is a cost of at most 2%, ratio >= 0.98).

A scene or binary that is missing or fails is listed with the reason; the exit status is then 1.

Usage: scripts/bench_renderer.py [--pbrt build/pbrt] [--upstream U] [--patched P]
           [--table T] [--spp 8] [--reps 3] [--cost-reps 7] [--cost-spp 32]
           [--scenes NAME ...] [--shared ../shared] [--box-spp 256] [--box-reps 2]
           [--no-mitsuba] [--no-cost] [--upstream-path]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "python"))
from wavelength_pdf.evaluation.scene_edit import edit_scene  # noqa: E402

CHECK_DIR = ROOT.parent / "upstream-check"  # scripts/check_upstream_patch.sh's default
# The evaluation scenes (../shared/scenes/README.md), the Cornell box first.
SCENES = ("cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase", "glass-of-water")
SIZE = (256, 256)
MAXDEPTH = 5
TARGET_RATIO = 0.98  # a table costs at most 2% per path
BOX_PBRT = ROOT / "scenes" / "cornell-box" / "scene.pbrt"  # 256x256, maxdepth 5
BOX_XML = ROOT / "scenes" / "cornell-box" / "scene.xml"
MITSUBA_VARIANT = "llvm_ad_spectral"
MITSUBA_MAX_DEPTH = MAXDEPTH + 1  # Mitsuba counts the camera segment (see above)
MITSUBA_PASS_SPP = 64
# The Mitsuba render, run in its own process so that its CPU time is measured alone.
MITSUBA_WORKER = r"""
import sys
sys.path.insert(0, sys.argv[1])
import wavelength_pdf.mitsuba.llvm as llvm
llvm.ensure_llvm_path()  # before the llvm backend starts
import mitsuba as mi
mi.set_variant(sys.argv[2])
xml, spp, per_pass, depth = sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
scene = mi.load_file(xml, width="256", height="256", max_depth=depth, spp=str(per_pass))
done = 0
while done < spp:
    n = min(per_pass, spp - done)
    img = mi.render(scene, spp=n, seed=done)
    done += n
import drjit as dr
dr.eval(img)
dr.sync_thread()
"""


class BenchError(RuntimeError):
    pass


def bench_copy(scene: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    """A copy of ``scene`` at 256x256 with maximum depth 5."""
    return edit_scene(scene, None, out, resolution=SIZE, maxdepth=MAXDEPTH)


def render_cpu(binary: pathlib.Path, scene: pathlib.Path, spp: int, extra: list[str],
               out: pathlib.Path, nthreads: int) -> float:
    cmd = [str(binary), "--quiet", "--spp", str(spp), "--seed", "1", "--nthreads", str(nthreads),
           *extra, "--outfile", str(out), str(scene)]
    return child_cpu(cmd, binary.name)


def process_throughput(binary: pathlib.Path, scene: pathlib.Path, spp: int, extra: list[str],
                       tmp: pathlib.Path) -> float:
    """M paths per CPU-second of one whole single-threaded render (loading included)."""
    cpu = render_cpu(binary, scene, spp, extra, tmp / "c.exr", 1)
    return SIZE[0] * SIZE[1] * spp / max(cpu, 1e-9) * 1e-6


def throughput(binary: pathlib.Path, scene: pathlib.Path, spp: int, extra: list[str],
               tmp: pathlib.Path, nthreads: int) -> float:
    """M paths per CPU-second from a render at spp and one at 3 spp (loading cancels)."""
    c1 = render_cpu(binary, scene, spp, extra, tmp / "a.exr", nthreads)
    c3 = render_cpu(binary, scene, 3 * spp, extra, tmp / "b.exr", nthreads)
    paths = SIZE[0] * SIZE[1] * 2 * spp
    if not c3 > c1:
        raise BenchError(f"{binary.name}: CPU time did not grow with spp ({c1:.2f} s, {c3:.2f} s)")
    return paths / (c3 - c1) * 1e-6


def child_cpu(cmd: list[str], what: str) -> float:
    """Whole-process CPU seconds (user + system) of a child process; BenchError if it fails."""
    before = os.times()
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = os.times()
    if proc.returncode != 0:
        lines = [line for line in proc.stderr.splitlines() if line.strip()]
        raise BenchError(f"{what}: exit {proc.returncode}: {lines[-1] if lines else ''}")
    return (after.children_user - before.children_user) + (after.children_system - before.children_system)


def mitsuba_available() -> str | None:
    """None when Mitsuba 3 with an LLVM for its llvm variants can run, else the reason."""
    proc = subprocess.run([sys.executable, "-c", MITSUBA_WORKER.split("xml, spp")[0]
                           + "print(mi.variant())\n", str(ROOT / "python"), MITSUBA_VARIANT],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        lines = [line for line in proc.stderr.splitlines() if line.strip()]
        return lines[-1] if lines else f"exit {proc.returncode}"
    return None


def crosscheck_box(pbrt: pathlib.Path, spp: int, reps: int, nthreads: int, tmp: pathlib.Path,
                   mitsuba: bool) -> bool:
    """The Mitsuba cross-check box: whole-process CPU seconds of pbrt and Mitsuba, alternating."""
    paths = SIZE[0] * SIZE[1] * spp
    print(f"\nMitsuba cross-check box ({BOX_PBRT.relative_to(ROOT)} / {BOX_XML.name}): "
          f"{SIZE[0]}x{SIZE[1]}, {spp} spp, pbrt maxdepth {MAXDEPTH} = Mitsuba max_depth "
          f"{MITSUBA_MAX_DEPTH}, default Russian roulette; whole-process CPU seconds, "
          f"{reps} alternating reps", flush=True)
    runners = {"this pbrt": lambda: child_cpu(
        [str(pbrt), "--quiet", "--spp", str(spp), "--seed", "1", "--nthreads", str(nthreads),
         "--outfile", str(tmp / "box.exr"), str(BOX_PBRT)], "pbrt")}
    if mitsuba:
        reason = mitsuba_available()
        if reason:
            print(f"  Mitsuba {MITSUBA_VARIANT} not measured: {reason}")
        else:
            runners[f"mitsuba {MITSUBA_VARIANT}"] = lambda: child_cpu(
                [sys.executable, "-c", MITSUBA_WORKER, str(ROOT / "python"), MITSUBA_VARIANT,
                 str(BOX_XML), str(spp), str(MITSUBA_PASS_SPP), str(MITSUBA_MAX_DEPTH)], "mitsuba")
    cpu: dict[str, list[float]] = {r: [] for r in runners}
    try:
        for rep in range(reps):
            for r in (list(runners) if rep % 2 == 0 else list(reversed(runners))):
                cpu[r].append(runners[r]())
    except BenchError as e:
        print(f"  failed: {e}")
        return False
    med = {r: statistics.median(v) for r, v in cpu.items()}
    for r, c in med.items():
        print(f"  {r:28s} {c:7.2f} CPU-s  {paths / c * 1e-6:6.3f} M paths per CPU-second "
              f"(runs {', '.join(f'{x:.2f}' for x in cpu[r])})")
    if len(med) == 2:
        m = med[f"mitsuba {MITSUBA_VARIANT}"]
        print(f"  ratio (Mitsuba CPU-s / pbrt CPU-s): {m / med['this pbrt']:.2f}")
    return True


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pbrt", type=pathlib.Path, default=ROOT / "build" / "pbrt")
    ap.add_argument("--upstream", type=pathlib.Path, default=CHECK_DIR / "unpatched" / "build" / "pbrt",
                    help="unpatched upstream pbrt-v4 (default: the check script's build)")
    ap.add_argument("--patched", type=pathlib.Path, default=CHECK_DIR / "patched" / "build" / "pbrt",
                    help="patched upstream pbrt-v4, for the table's cost (default: the check script's)")
    ap.add_argument("--table", type=pathlib.Path, default=None,
                    help="table for the cost measurement (default: the check script's LSPDD 2482 "
                         "table, else tests/data/tables/tri-band-fluorescent-optimized.csv)")
    ap.add_argument("--spp", type=int, default=8, help="spp of the smaller render (default 8)")
    ap.add_argument("--reps", type=int, default=3, help="alternating repetitions per scene (default 3)")
    ap.add_argument("--cost-reps", type=int, default=7, help="pairs for the table's cost (default 7)")
    ap.add_argument("--cost-spp", type=int, default=32, help="spp of the cost renders (default 32)")
    ap.add_argument("--nthreads", type=int, default=2)
    ap.add_argument("--shared", type=pathlib.Path, default=ROOT.parent / "shared")
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--box-spp", type=int, default=256, help="spp on the Mitsuba cross-check box (default 256)")
    ap.add_argument("--box-reps", type=int, default=2, help="alternating reps on the box (default 2)")
    ap.add_argument("--no-mitsuba", action="store_true", help="the box with this pbrt only")
    ap.add_argument("--no-box", action="store_true", help="skip the Mitsuba cross-check box")
    ap.add_argument("--no-cost", action="store_true", help="skip the table's cost in patched upstream")
    ap.add_argument("--upstream-path", action="store_true",
                    help="render scenes written for another integrator (bdpt) with \"path\" in upstream "
                         "too, so that both renderers run the same algorithm")
    args = ap.parse_args()
    if args.box_spp < 1 or args.box_reps < 1:
        print("bench_renderer: --box-spp and --box-reps must be at least 1", file=sys.stderr)
        return 1
    if args.spp < 1 or args.reps < 1 or args.cost_reps < 1:
        print("bench_renderer: --spp, --reps and --cost-reps must be at least 1", file=sys.stderr)
        return 1
    if not args.pbrt.is_file():
        print(f"bench_renderer: {args.pbrt} not found (build it with scripts/setup.sh)", file=sys.stderr)
        return 1
    if not (args.shared / "scenes").is_dir():
        print(f"bench_renderer: no scenes under {args.shared / 'scenes'}", file=sys.stderr)
        return 1
    renderers = {"this pbrt": args.pbrt}
    if args.upstream.is_file():
        renderers["upstream"] = args.upstream
    else:
        print(f"bench_renderer: no upstream binary at {args.upstream} "
              "(scripts/check_upstream_patch.sh builds it); measuring this pbrt only", file=sys.stderr)
    failures = 0 if "upstream" in renderers else 1
    print(f"{SIZE[0]}x{SIZE[1]}, maxdepth {MAXDEPTH}, {args.spp} and {3 * args.spp} spp, "
          f"{args.nthreads} threads, {args.reps} alternating reps; M paths per CPU-second (medians)")
    for name, path in renderers.items():
        print(f"  {name}: {path}")
    print(f"  {'scene':15s} {'this pbrt':>10s} {'upstream':>10s} {'ratio':>7s}")
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = pathlib.Path(tmpdir)
        for name in args.scenes:
            src = args.shared / "scenes" / name / "scene-v4.pbrt"
            if not src.is_file():
                print(f"  {name:15s} missing: {src}")
                failures += 1
                continue
            scene = bench_copy(src, tmp / name / "scene.pbrt")
            integrator = re.search(r'Integrator\s+"([^"]+)"', scene.read_text())
            other_integrator = bool(integrator and integrator[1] not in ("path", "volpath"))
            scenes = {r: scene for r in renderers}
            if other_integrator and args.upstream_path and "upstream" in renderers:
                path_copy = tmp / name / "scene-path.pbrt"
                path_copy.write_text(re.sub(r'Integrator\s+"[^"]+"', 'Integrator "path"', scene.read_text(), count=1))
                scenes["upstream"] = path_copy
            runs: dict[str, list[float]] = {r: [] for r in renderers}
            try:
                for rep in range(args.reps):
                    order = list(renderers) if rep % 2 == 0 else list(reversed(renderers))
                    for r in order:
                        runs[r].append(throughput(renderers[r], scenes[r], args.spp, [], tmp, args.nthreads))
            except BenchError as e:
                print(f"  {name:15s} failed: {e}")
                failures += 1
                continue
            med = {r: statistics.median(v) for r, v in runs.items()}
            note = ""
            if other_integrator:
                note = ("  (written for {0}: both render it with path)" if scenes.get("upstream") is not scene
                        else "  (upstream: {0}; this pbrt renders it with path)").format(integrator[1])
            if "upstream" in med:
                print(f"  {name:15s} {med['this pbrt']:10.3f} {med['upstream']:10.3f} "
                      f"{med['this pbrt'] / med['upstream']:7.2f}{note}", flush=True)
            else:
                print(f"  {name:15s} {med['this pbrt']:10.3f} {'-':>10s} {'-':>7s}")

        if not args.no_box and not crosscheck_box(args.pbrt, args.box_spp, args.box_reps, args.nthreads,
                                                  tmp, not args.no_mitsuba):
            failures += 1
        if args.no_cost:
            return 1 if failures else 0

        # The table's cost in patched upstream: visible vs table, alternating pairs.
        table = args.table
        if table is None:
            table = CHECK_DIR / "check" / "table-2482.csv"
            if not table.is_file():
                table = ROOT / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
        if not args.patched.is_file():
            print(f"\nno patched upstream binary at {args.patched}: the table's cost is not measured")
            return 1
        src = args.shared / "scenes" / "cornell-box" / "scene-v4.pbrt"
        scene = bench_copy(src, tmp / "cost" / "scene.pbrt")
        samplers = {"visible": [], "table": ["--wavelength-pdf", str(table)]}
        runs = {s: [] for s in samplers}
        print(f"\npatched upstream {args.patched}: Cornell box 256x256, maxdepth 5, {args.cost_spp} spp, "
              f"1 thread, visible vs table {table.name}, {args.cost_reps} alternating pairs "
              "(CPU time of the whole process; loading is the same for both)", flush=True)
        try:
            for rep in range(args.cost_reps):
                order = list(samplers) if rep % 2 == 0 else list(reversed(samplers))
                for s in order:
                    runs[s].append(process_throughput(args.patched, scene, args.cost_spp, samplers[s], tmp))
                print(f"  pair {rep + 1}: visible {runs['visible'][-1]:.4f}, table {runs['table'][-1]:.4f} "
                      f"M paths/CPU-s, ratio {runs['table'][-1] / runs['visible'][-1]:.4f}", flush=True)
        except BenchError as e:
            print(f"  failed: {e}")
            return 1
        ratios = [t / v for t, v in zip(runs["table"], runs["visible"])]
        ratio = statistics.median(ratios)
        print(f"  median ratio table / visible: {ratio:.4f} (cost per path {100 * (1 / ratio - 1):+.2f}%; "
              f"target ratio >= {TARGET_RATIO}; spread {min(ratios):.4f}..{max(ratios):.4f})")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
