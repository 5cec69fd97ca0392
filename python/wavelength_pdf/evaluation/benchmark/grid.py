"""What the benchmark renders (design §6.7): scenes, lamps, samplers and the two sweeps.

Every compared sampler is a table read by ``--wavelength-pdf`` (one code path, so a comparison
is of distributions and nothing else): the simple samplers of design §1.7 (``uniform``,
``visible``, ``spd``, ``luminance``, ``xyz``), the optimizer's start (``start``), the optimized
table (``optimized``) and, for the lamps they were made for, the tables of earlier work
(``reference``). Beside them, ``visible-builtin`` is pbrt-v4's own visible sampling
(``--wavelength-sampling visible``), which the ``visible`` table must match within noise, and
the ``floor`` is the ``spd`` table traced with ``--wavelength-repeats`` (the error left when
wavelength sampling adds almost none).

Two sweeps, so that the grid fits a few CPU-hours at reduced resolution: every lamp on two
cheap scenes (``lamps``), and every scene under a handful of lamps of each kind (``scenes``),
with the scene's own low-discrepancy pixel sampler and with the independent sampler.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Sequence

from wavelength_pdf.data import CHECKOUT

#: The shared reference material (scenes, LSPDD spectra, earlier tables), by default
#: ``../shared`` beside the checkout; ``$WAVELENGTH_PDF_SHARED`` names another folder.
SHARED = Path(os.environ.get("WAVELENGTH_PDF_SHARED", CHECKOUT.parent / "shared"))


@dataclass(frozen=True)
class SceneSpec:
    """A scene of the benchmark."""

    key: str
    #: ``shared:PATH`` (under the shared folder) or ``repo:PATH`` (under the checkout).
    source: str
    #: What it tests, for the report.
    about: str
    #: The scene keeps its own emitters (several kinds of lamp) instead of being lit by one.
    own_lamps: bool = False
    #: The glass of water: the project's water body goes into the glass (its own is missing).
    water: bool = False
    #: The benchmark's film size: (w, h), or a factor on the scene's own.
    resolution: tuple[int, int] | float = 0.05

    def path(self, shared: Path = SHARED) -> Path:
        kind, _, rel = self.source.partition(":")
        return (shared if kind == "shared" else CHECKOUT) / rel

    def available(self, shared: Path = SHARED) -> bool:
        if self.water:
            from wavelength_pdf.evaluation.glass_of_water import WATER_PLY

            if not WATER_PLY.is_file():
                return False
        return self.path(shared).is_file()


@dataclass(frozen=True)
class LampSpec:
    """A lamp of the benchmark: a spectrum spec (design §7) and what kind of lamp it is."""

    key: str
    #: ``shared:PATH`` for an LSPDD export under the shared folder, else a spec (``cie:FL2``).
    source: str
    kind: str
    #: A spiky lamp (lines or narrow bands), where the method is meant to pay.
    spiky: bool
    #: The 4 x 81 table of earlier work made for this lamp (file in tables/reference-4x81).
    reference: str | None = None

    def spec(self, shared: Path = SHARED) -> str:
        kind, _, rel = self.source.partition(":")
        return str(shared / rel) if kind == "shared" else self.source

    def available(self, shared: Path = SHARED) -> bool:
        kind, _, rel = self.source.partition(":")
        return kind != "shared" or (shared / rel).is_file()


SCENES: dict[str, SceneSpec] = {s.key: s for s in [
    SceneSpec("cornell-box", "shared:scenes/cornell-box/scene-v4.pbrt", "diffuse, one area light"),
    SceneSpec("teapot", "shared:scenes/teapot/scene-v4.pbrt", "coated diffuse, checker texture, constant sky"),
    SceneSpec("veach-mis", "shared:scenes/veach-mis/scene-v4.pbrt", "rough conductors, sphere lights"),
    SceneSpec("staircase", "shared:scenes/staircase/scene-v4.pbrt", "textures, bump maps, glass; long paths"),
    SceneSpec("veach-bidir", "shared:scenes/veach-bidir/scene-v4.pbrt", "conductor, dielectric; caustics"),
    SceneSpec("glass-of-water", "shared:scenes/glass-of-water/scene-v4.pbrt",
              "dielectric interfaces with the project's water body", water=True),
    SceneSpec("colorchecker", "repo:scenes/benchmark/colorchecker/scene.pbrt",
              "the 24 ColorChecker patches, direct light only", resolution=0.1),
    SceneSpec("prism", "repo:scenes/benchmark/prism/scene.pbrt", "a dispersive prism spreading the lamp's lines", resolution=0.2),
    SceneSpec("tinted-glass", "repo:scenes/benchmark/tinted-glass/scene.pbrt",
              "light filtered by coloured translucent panes", resolution=0.2),
    SceneSpec("lamp-room", "repo:scenes/benchmark/lamp-room/scene.pbrt",
              "sodium, LED and metal-halide lamps in separate places", own_lamps=True, resolution=0.2),
    SceneSpec("window-room", "repo:scenes/benchmark/window-room/scene.pbrt",
              "daylight through a window and a fluorescent lamp inside", own_lamps=True, resolution=0.2),
    SceneSpec("night-street", "repo:scenes/benchmark/night-street/scene.pbrt",
              "a street under sodium, LED and metal-halide lamps", own_lamps=True, resolution=0.2),
    SceneSpec("two-lamp-box", "repo:scenes/cornell-box-two-lamps/scene.pbrt",
              "the project's box under two lamps of different kinds", own_lamps=True),
    SceneSpec("project-box", "repo:scenes/cornell-box/scene.pbrt", "the project's own Cornell box"),
]}


def _lspdd(key: str, kind: str, spiky: bool, reference: str | None = None) -> LampSpec:
    return LampSpec(key, f"shared:spectra/lspdd/{key}.csv", kind, spiky, reference)


LAMPS: dict[str, LampSpec] = {l.key: l for l in [
    # LSPDD exports (../shared/spectra/lspdd; numbers about them may be published, the
    # spectra may not be copied). The kind is the export's "Category".
    _lspdd("2469", "LED", True), _lspdd("2503", "LED", True), _lspdd("2542", "LED", True),
    _lspdd("2619", "LED", True),
    _lspdd("2482", "fluorescent", True, "fluorescent-ipopt"), _lspdd("2510", "fluorescent", True),
    _lspdd("2481", "metal halide", True), _lspdd("2641", "metal halide", True, "Philips_MH"),
    _lspdd("2536", "sodium", True),
    _lspdd("2472", "incandescent", False), _lspdd("2480", "incandescent", False),
    _lspdd("2629", "daylight", False, "sun"),
    _lspdd("2639", "sensitivity curve", False, "Scotopic-2"),
    _lspdd("2689", "sensitivity curve", True, "Honeybees-2"),
    _lspdd("2659", "incandescent", False, "A_Std"), _lspdd("2661", "daylight", False, "D65"),
    _lspdd("2671", "fluorescent", True), _lspdd("2690", "fluorescent", True),
    _lspdd("2694", "sodium", True),
    # colour-science's CIE illuminants and light sources (design §3.2).
    *[LampSpec(f"cie-FL{i}", f"cie:FL{i}", "fluorescent", True, "FL8" if i == 8 else None)
      for i in range(1, 13)],
    LampSpec("cie-HP1", "cie:HP1", "sodium", True), LampSpec("cie-HP2", "cie:HP2", "sodium", True),
    *[LampSpec(f"cie-HP{i}", f"cie:HP{i}", "metal halide", True) for i in (3, 4, 5)],
    *[LampSpec(f"cie-LED-{n}", f"cie:LED-{n}", "LED", True)
      for n in ("B1", "B2", "B3", "B4", "B5", "BH1", "RGB1", "V1", "V2")],
    LampSpec("cie-D65", "cie:D65", "daylight", False), LampSpec("cie-A", "cie:A", "incandescent", False),
    LampSpec("lamp-LPS", "lamp:LPS", "sodium", True), LampSpec("lamp-Mercury", "lamp:Mercury", "mercury", True),
]}

#: The table optimized for a pixel of 64 stratified samples (``optimize --objective
#: stratified``, design §4.6) rather than one path (J): one per lamp, for every spp.
PIXEL = "optimized-pixel"
#: Every simple sampler is a table of design §1.7; with the optimizer's start and the optimized
#: (and reference) tables, the rows every job compares.
TABLE_ROWS = ("uniform", "visible", "spd", "luminance", "xyz", "start", "optimized", PIXEL)
#: The table optimized for the scene's own material colours (``optimize --reflectances scene``,
#: design §4.5), on the scene sweep's low-discrepancy jobs under spiky lamps.
SCENE_COLOURS = "optimized-scene"
#: The same for a pixel of 64 stratified samples (``--objective stratified --reflectances
#: scene``): both of the objective's models of the image at once, where SCENE_COLOURS is.
PIXEL_SCENE = "optimized-pixel-scene"
#: The rows optimized for the scene's own colours (their tables live in the job's folder).
COLOUR_ROWS = (SCENE_COLOURS, PIXEL_SCENE)
#: The lamp's table optimized for a fixed, generic colour set (``optimize --reflectances
#: colorchecker``: the ColorChecker's 24 patches, design §4.5) rather than a white surface:
#: one per lamp like ``optimized``, rendered on the scene sweep, whose scenes show other
#: colours, to see whether colours the table was not made for still gain over white.
GENERIC_COLOURS = "optimized-colorchecker"
#: The table a user gets for the job's image without an optimizer run of their own beyond
#: J's: ``wavelength-pdf choose SCENE optimized.csv --polish --spread --spp N``, the best by
#: the image's predicted error (design §6.8) of the simple samplers, J's table and the ``spd``
#: and J's tables polished for the scene's pixels (design §4.6), one table for each spp N the
#: job renders at (:func:`image_table_name`), as a user runs ``choose`` at the spp they render
#: at. On the lamp sweep's two scenes (each choice at 64 spp about 12 s on the ColorChecker's
#: 32 x 24 and 40 s on the Cornell box's 51 x 51; at 16 spp, with the polish's continuation
#: from 64 spp, about three times that). The scene sweep's copies could carry it too (a spread is
#: 21 x 21 floats per lit pixel, 200 MB at 320 x 180), not yet measured there.
IMAGE = "optimized-image"


def image_table_name(spp: int) -> str:
    """The file name of a job's :data:`IMAGE` table for ``spp``."""
    return f"{IMAGE}-{spp}spp.csv"


#: Every row a job can list (a lamp's earlier-work ``reference`` table, the check row and the
#: floor are added by the job's plan, not listed).
ROWS = (*TABLE_ROWS, *COLOUR_ROWS, GENERIC_COLOURS, IMAGE)
#: The simple samplers (no optimizer): "the best simple sampler" is the best of these.
SIMPLE = ("uniform", "visible", "spd", "luminance", "xyz")
#: Check row: pbrt-v4's own visible sampling, which the ``visible`` table must match.
BUILTIN = "visible-builtin"
#: The floor's sampler and its wavelength repeats.
FLOOR = "floor"
FLOOR_TABLE = "spd"

#: The pixel samplers of the scene sweep: low-discrepancy and independent.
PIXEL_SAMPLERS = ("sobol", "independent")
#: The scene sweep's lamps: two of each spiky kind and two smooth ones.
SCENE_SWEEP_LAMPS = ("2482", "cie-FL2", "2641", "2536", "2469", "cie-D65")
#: The scene sweep's sample counts; the independent pixel sampler's jobs stop at the second
#: (at 256 spp they would take half the grid's CPU time and add the least).
SPP = (16, 64, 256)
#: The headline lamp (the compact fluorescent 2482): each scene's table for its own material
#: colours is optimized under it (scenes with their own lamps get one too), its jobs render
#: first, are timed, and are plotted.
HEADLINE_LAMP = "2482"
#: The lamp sweep's two cheap scenes.
LAMP_SWEEP_SCENES = ("colorchecker", "cornell-box")


@dataclass(frozen=True)
class Job:
    """One scene under one lamp (``lamp`` None: its own emitters), one pixel sampler."""

    scene: SceneSpec
    lamp: LampSpec | None
    #: The pixel sampler every image uses: "sobol" (low-discrepancy, the evaluation scenes'
    #: own) or "independent".
    pixel_sampler: str = "sobol"
    #: Film size (w, h), or a factor on the scene's own; None: the scene's benchmark size.
    resolution: tuple[int, int] | float | None = None
    spp: tuple[int, ...] = (16, 64, 256)
    #: Two seeds make a pair (their difference has twice one image's variance).
    seeds: tuple[int, int] = (1, 2)
    truth_spp: int = 1024
    floor_repeats: int = 8
    #: The spp at which the floor (``floor_repeats`` times the cost) and the check row
    #: (pbrt-v4's own visible sampling) are rendered.
    floor_spp: tuple[int, ...] = (16, 64)
    check_spp: tuple[int, ...] = (64,)
    rows: tuple[str, ...] = TABLE_ROWS
    sweep: str = "scenes"
    #: Every render with ``--wavelength-net`` (design §5.2), reference and floor included.
    wavelength_net: bool = False
    #: Each polish's budget of evaluations when the :data:`IMAGE` table is made (``choose
    #: --polish-evaluations``); None: the polish's default.
    polish_evaluations: int | None = None

    @property
    def size(self) -> tuple[int, int] | float:
        return self.scene.resolution if self.resolution is None else self.resolution

    @property
    def lamp_key(self) -> str:
        return self.lamp.key if self.lamp else "own"

    @property
    def name(self) -> str:
        return f"{self.scene.key}/{self.lamp_key}/{self.pixel_sampler}"


@dataclass
class GridSpec:
    """The whole benchmark: its jobs and where the shared material is."""

    jobs: list[Job] = field(default_factory=list)
    shared: Path = SHARED
    skipped: list[str] = field(default_factory=list)


def full_grid(shared: Path = SHARED) -> GridSpec:
    """The benchmark of docs/benchmark.md: the lamp sweep and the scene sweep (a job in both
    runs once, its ``sweep`` naming both)."""
    g = GridSpec(shared=shared)
    for s in LAMP_SWEEP_SCENES:
        for lamp in LAMPS.values():
            # The ColorChecker is what its patches show: tables for them too (the objective's
            # colours, design §4.5, measured under every lamp).
            # The floor (eight renders' paths) at both spp, so that the 64 spp jobs are
            # measured against a floor of their own, not the 16 spp one scaled: on the Cornell
            # box the scaled one was about a tenth too low (docs/benchmark.md, "The table for
            # the image at each spp, and on the Cornell box").
            add(g, Job(SCENES[s], lamp, "sobol", spp=(16, 64), sweep="lamps", floor_spp=(16, 64),
                       rows=TABLE_ROWS + (COLOUR_ROWS if s == "colorchecker" else ()) + (IMAGE,)))
    for s in SCENES.values():
        if s.key in ("project-box", "two-lamp-box"):
            continue
        lamps = [None] if s.own_lamps else [LAMPS[k] for k in SCENE_SWEEP_LAMPS]
        for lamp in lamps:
            for ps in PIXEL_SAMPLERS:
                colours = ps == "sobol" and (lamp is None or lamp.key == HEADLINE_LAMP)
                add(g, Job(s, lamp, ps, sweep="scenes", spp=SPP if ps == "sobol" else SPP[:2],
                           rows=TABLE_ROWS + (COLOUR_ROWS if colours else ())
                           + ((GENERIC_COLOURS,) if ps == "sobol" else ())))
    return g


def small_grid(shared: Path = SHARED) -> GridSpec:
    """The suite's version: the project's own box under its tri-band lamp with both pixel
    samplers and the two-lamp box under its own lamps, tiny images and few samples, the simple
    samplers and the optimizer's start (no optimization, no shared material needed), and on
    the low-discrepancy box the table ``choose --polish --spread`` picks (IMAGE: polishing
    needs no optimizer run; short polishes, for the suite's time)."""
    g = GridSpec(shared=shared)
    tri = LampSpec("tri-band", str(CHECKOUT / "spectra" / "tri-band-fluorescent.spd"), "fluorescent", True)
    small = dict(resolution=(12, 12), spp=(4, 16), truth_spp=1024, floor_repeats=4, floor_spp=(4, 16),
                 check_spp=(4, 16), sweep="small", polish_evaluations=40)
    for ps in PIXEL_SAMPLERS:
        add(g, Job(SCENES["project-box"], tri, ps, rows=(*SIMPLE, "start", IMAGE), **small))
    add(g, Job(SCENES["two-lamp-box"], None, "sobol", rows=SIMPLE, **small))
    return g


def add(g: GridSpec, job: Job) -> None:
    """Add ``job`` unless its scene or lamp is not available (noted in ``g.skipped``); a job
    already there (same scene, lamp and pixel sampler) is kept once, in both sweeps, with the
    union of their sample counts."""
    for i, other in enumerate(g.jobs):
        if other.name == job.name:
            if job.sweep not in other.sweep.split("+"):
                g.jobs[i] = replace(other, sweep=f"{other.sweep}+{job.sweep}",
                                    spp=tuple(sorted(set(other.spp) | set(job.spp))),
                                    floor_spp=tuple(sorted(set(other.floor_spp) | set(job.floor_spp))),
                                    rows=other.rows + tuple(r for r in job.rows if r not in other.rows))
            return
    if job.scene.water and not job.scene.available(g.shared) and job.scene.path(g.shared).is_file():
        g.skipped.append(f"{job.name}: the project's water body is missing (scripts/make_benchmark_scenes.py)")
    elif not job.scene.available(g.shared):
        g.skipped.append(f"{job.name}: {job.scene.path(g.shared)} is not present")
    elif job.lamp is not None and not job.lamp.available(g.shared):
        g.skipped.append(f"{job.name}: {job.lamp.spec(g.shared)} is not present")
    else:
        g.jobs.append(job)


def with_rows(g: GridSpec, rows: Sequence[str] | None) -> GridSpec:
    """Each job with only those of its rows named in ``rows`` (the floor and the reference
    are not rows: every job keeps them); None keeps every row."""
    if rows is None:
        return g
    unknown = sorted(set(rows) - set(ROWS))
    if unknown:
        raise ValueError(f"unknown rows {', '.join(unknown)}; the rows are {', '.join(ROWS)}")
    return GridSpec([replace(j, rows=tuple(r for r in j.rows if r in rows)) for j in g.jobs],
                    g.shared, g.skipped)


def with_wavelength_net(g: GridSpec, on: bool) -> GridSpec:
    """Every job's renders with ``--wavelength-net`` (``on``), or as they are."""
    return GridSpec([replace(j, wavelength_net=True) for j in g.jobs], g.shared, g.skipped) if on else g


def select(g: GridSpec, only: list[str] | None) -> GridSpec:
    """The jobs whose name (``scene/lamp/pixel-sampler``) starts with one of ``only``, or
    whose sweep is named there."""
    if not only:
        return g
    keep = [j for j in g.jobs if any(j.name.startswith(o) or o in j.sweep.split("+") for o in only)]
    return GridSpec(keep, g.shared, g.skipped)
