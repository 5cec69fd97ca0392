"""The evaluation (design §6) with Mitsuba 3 as the renderer: ``--renderer mitsuba``.

The protocol is the one of :mod:`.protocol` (same table, same rows, same plots); what differs
is the scene and how an image is made:

- The scene is a Mitsuba 3 XML file that declares its lamp as parameters (``lamp_wavelengths``,
  ``lamp_values``, ``lamp_luminance``), as ``scenes/cornell-box/scene.xml`` does. The lamp's
  spectrum, cut to the table's range, is scaled the way pbrt-v4 scales an area light (to a
  luminance of ``lamp_luminance``), so that both renderers make the same image.
- The samplers: ``uniform`` is Mitsuba's stock ``uniform`` spectrum as the sensor's ``srf``
  over the table's range (stratified uniform: Mitsuba shifts the four lanes by 1/4), ``visible``
  is Mitsuba's default (no ``srf``: its visible-range fit, stratified the same way), ``table``
  is the ``wavelength_table`` plugin (:mod:`wavelength_pdf.mitsuba`).
- An image is rendered in passes of at most ``PASS_SAMPLES`` paths, each with its own seed, and
  averaged (the llvm variants keep a whole pass's paths in memory); its time is the wall-clock
  time of loading and rendering, Dr.Jit's kernel compilation included (its kernel cache makes
  that small after the first image of a sampler).
"""
from __future__ import annotations

import json
import os
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Callable

import numpy as np

from wavelength_pdf.evaluation.protocol import Config, Evaluation, ensure_table, score
from wavelength_pdf.evaluation.render import Render, RenderError, file_digest
from wavelength_pdf.exr import read_rgb, write_rgb
from wavelength_pdf.spectra import Spectrum, SpectrumError
from wavelength_pdf.table import read_table

#: Mitsuba 3 divides the film's XYZ by this integral of its CIE 1931 ybar
#: (1 / MI_CIE_Y_NORMALIZATION, include/mitsuba/core/spectrum.h of Mitsuba 3.9).
MITSUBA_CIE_Y_INTEGRAL = 106.7502593994140625
#: The variant of the evaluation (CPU, vectorized).
DEFAULT_VARIANT = "llvm_ad_spectral"
#: Paths per render pass (pixels x spp), which bounds the llvm variants' memory.
PASS_SAMPLES = 1 << 22
#: The scene parameters the backend sets.
LAMP_PARAMS = ("lamp_wavelengths", "lamp_values")


def photometric(wavelengths: np.ndarray, values: np.ndarray) -> float:
    """pbrt-v4's SpectrumToPhotometric: sum of the CIE 1931 ybar times S at 360, 361, ..., 830 nm."""
    import colour

    lam = np.arange(360, 831)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    return float(np.sum(cmfs.values[:, 1] * np.interp(lam, wavelengths, values, left=0.0, right=0.0)))


def lamp_radiance(spectrum: Spectrum, luminance: float, lo: float | None = None,
                  hi: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Wavelengths [nm] and Mitsuba radiance values of a lamp, optionally cut to [lo, hi].

    pbrt-v4 divides an area light's spectrum by :func:`photometric` and multiplies it by its
    "scale"; Mitsuba then divides the film's XYZ by ``MITSUBA_CIE_Y_INTEGRAL``, so the values
    here are S * luminance * MITSUBA_CIE_Y_INTEGRAL / photometric(S): both renderers show the
    lamp with Y = ``luminance``.
    """
    lam, val = np.asarray(spectrum.wavelengths, float), np.asarray(spectrum.values, float)
    if lo is not None and hi is not None:
        inside = (lam > lo) & (lam < hi)
        grid = np.concatenate([[lo], lam[inside], [hi]])
        lam, val = grid, np.interp(grid, lam, val, left=0.0, right=0.0)
    y = photometric(lam, val)
    if not (y > 0):
        raise SpectrumError(f"{spectrum.source}: no luminous energy"
                            + (f" inside {lo:g}-{hi:g} nm" if lo is not None else ""))
    return lam, val * (luminance * MITSUBA_CIE_Y_INTEGRAL / y)


def _defaults(root: ET.Element) -> dict[str, str]:
    return {d.get("name"): d.get("value") for d in root.iter("default")}


def read_scene(path: Path) -> ET.Element:
    """Parse a Mitsuba XML scene that ``--renderer mitsuba`` can use, or raise with the reason."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(2, "no such scene file", str(path))
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise RenderError(f"{path}:{e.position[0]}: not well-formed XML ({e})") from None
    missing = [p for p in (*LAMP_PARAMS, "lamp_luminance") if p not in _defaults(root)]
    if root.tag != "scene" or missing:
        raise RenderError(f"{path}:1: a scene for --renderer mitsuba must be a Mitsuba 3 <scene> that "
                          f"declares <default> lamp parameters; missing {', '.join(missing) or '<scene>'}")
    if root.find("sensor") is None:
        raise RenderError(f"{path}:1: the scene has no <sensor>")
    return root


def sampler_srf(method: str, table: Path | None, lo: float, hi: float) -> ET.Element | None:
    """The sensor's ``srf`` element of a sampler of the comparison (None: Mitsuba's default)."""
    if method == "visible":
        return None
    if method == "uniform":
        srf = ET.Element("spectrum", type="uniform", name="srf")
        for k, v in (("value", 1), ("wavelength_min", lo), ("wavelength_max", hi)):
            ET.SubElement(srf, "float", name=k, value=f"{v:.17g}")
        return srf
    if method == "table":
        if table is None:
            raise ValueError("the table sampler needs a table")
        srf = ET.Element("texture", type="wavelength_table", name="srf")
        ET.SubElement(srf, "string", name="filename", value=str(Path(table).resolve()))
        return srf
    raise ValueError(f"unknown method {method!r}; choose from uniform, visible, table")


def write_variant(scene: Path, out: Path, method: str, table: Path | None, lo: float, hi: float,
                  sampler: str | None = None) -> Path:
    """A copy of ``scene`` at ``out`` with the sampler's ``srf`` in its sensor and every file
    name made absolute (the copy lives elsewhere); ``sampler`` replaces the type of the
    sensor's sample generator (e.g. ``ldsampler``), None keeps it."""
    root = read_scene(scene)
    base = Path(scene).resolve().parent
    for el in root.iter("string"):
        if el.get("name") == "filename" and "$" not in (el.get("value") or ""):
            el.set("value", str((base / el.get("value")).resolve()))
    sensor = root.find("sensor")
    if sampler is not None:
        for el in sensor.iter("sampler"):
            el.set("type", sampler)
    for old in [c for c in sensor if c.get("name") == "srf"]:
        sensor.remove(old)
    srf = sampler_srf(method, table, lo, hi)
    if srf is not None:
        sensor.insert(0, srf)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    ET.ElementTree(root).write(tmp, encoding="unicode")
    os.replace(tmp, out)
    return out


def scene_params(scene: Path, spectrum: Spectrum, lo: float, hi: float,
                 resolution: tuple[int, int] | float | None) -> dict[str, str]:
    """The XML parameters of an evaluation render: the lamp and the film size."""
    d = _defaults(read_scene(scene))
    try:
        luminance = float(d["lamp_luminance"])
    except ValueError:
        raise RenderError(f"{scene}: lamp_luminance {d['lamp_luminance']!r} is not a number") from None
    lam, val = lamp_radiance(spectrum, luminance, lo, hi)
    params = {"lamp_wavelengths": ", ".join(f"{v:.10g}" for v in lam),
              "lamp_values": ", ".join(f"{v:.10g}" for v in val)}
    try:
        size = tuple(int(d.get(k, "256")) for k in ("width", "height"))
    except ValueError:
        raise RenderError(f"{scene}: the scene's default width/height are not integers") from None
    if isinstance(resolution, tuple):
        size = resolution
    elif resolution is not None:
        size = tuple(max(1, int(round(v * resolution))) for v in size)
    params.update(width=str(size[0]), height=str(size[1]))  # always: the passes need the pixel count
    return params


def _import(variant: str):
    import wavelength_pdf.mitsuba as wpm  # sets DRJIT_LIBLLVM_PATH before the llvm backend starts
    import mitsuba as mi

    mi.set_variant(variant)
    wpm.register(variant)
    return mi


def render_image(scene_xml: Path, params: dict[str, str], spp: int, seed: int,
                 variant: str = DEFAULT_VARIANT) -> np.ndarray:
    """Load and render a scene variant in passes; the (h, w, 3) linear sRGB image."""
    mi = _import(variant)
    w, h = int(params.get("width", 0)), int(params.get("height", 0))
    per_pass = spp if not (w and h) else max(1, min(spp, PASS_SAMPLES // (w * h)))
    passes = -(-spp // per_pass)
    total, done = None, 0
    for k in range(passes):
        n = min(per_pass, spp - done)
        try:
            scene = mi.load_file(str(scene_xml), **params, spp=str(n))
        except RuntimeError as e:
            raise RenderError(f"{scene_xml}: Mitsuba cannot load the scene: {e}") from None
        img = np.asarray(mi.render(scene, seed=seed * 7919 + k), dtype=np.float64)[..., :3]
        total = img * n if total is None else total + img * n
        done += n
    image = total / spp
    if not np.all(np.isfinite(image)):
        raise RenderError(f"{scene_xml}: the render has NaN or infinite pixels")
    return image


def render(scene_xml: Path, params: dict[str, str], out: Path, spp: int, seed: int,
           variant: str = DEFAULT_VARIANT, cache: bool = True) -> Render:
    """Render to ``out`` (EXR) unless an identical render is already there; time it."""
    out = Path(out)
    meta = out.with_suffix(".json")
    files = [scene_xml] + [Path(e.get("value")) for e in ET.parse(scene_xml).getroot().iter("string")
                           if e.get("name") == "filename" and Path(e.get("value") or "").is_file()]
    key = file_digest(*files, extra=json.dumps([params, spp, seed, variant]))
    if cache and out.is_file() and meta.is_file():
        m = json.loads(meta.read_text())
        if m.get("key") == key:
            return Render(out, float(m["seconds"]))
    start = time.perf_counter()
    image = render_image(scene_xml, params, spp, seed, variant)
    seconds = time.perf_counter() - start
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.stem}.tmp.exr")
    write_rgb(tmp, image)
    os.replace(tmp, out)
    meta.write_text(json.dumps({"key": key, "seconds": seconds, "variant": variant,
                                "cpus": os.cpu_count()}, indent=1))
    return Render(out, seconds)


def _scene_name(scene: Path) -> str:
    return Path(scene).parent.name or Path(scene).stem


def evaluate(scene: Path, spectrum: Spectrum, outdir: Path, config: Config = Config(), *,
             table: Path | None = None, scene_name: str | None = None,
             progress: Callable[[str], None] | None = None,
             optimizer_progress: Callable[[int, float], None] | None = None,
             variant: str = DEFAULT_VARIANT) -> Evaluation:
    """The protocol of :func:`.protocol.evaluate` with Mitsuba 3 rendering; same rows and files."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda msg: None)
    unknown = set(config.methods) - {"uniform", "visible", "table"}
    if unknown:
        raise ValueError(f"unknown methods {sorted(unknown)}; choose from uniform, visible, table")
    params = scene_params(scene, spectrum, config.lo, config.hi, config.resolution)  # checks the scene
    ev = Evaluation()
    ev.table = table or ensure_table(spectrum, outdir / "table.csv", config.lo, config.hi,
                                     progress=optimizer_progress)
    read_table(ev.table)  # a bad table stops here, before any render
    scenes = {m: write_variant(scene, outdir / f"scene-{m}.xml", m, ev.table, config.lo, config.hi)
              for m in {*config.methods, config.truth_method}}
    ev.scene = scenes.get("table", next(iter(scenes.values())))
    if config.nthreads:
        _import(variant)
        import drjit as dr

        dr.set_thread_count(config.nthreads)

    say(f"ground truth: {config.truth_method}, {config.truth_spp} spp")
    gt = render(scenes[config.truth_method], params,
                outdir / "renders" / f"truth-{config.truth_method}-{config.truth_spp}.exr",
                config.truth_spp, 10_000 + config.seed, variant)
    ev.truth, ev.truth_seconds = gt.image, gt.seconds
    truth = read_rgb(gt.image)
    name = scene_name or _scene_name(scene)
    seeds = [config.seed + k for k in range(max(1, config.seeds))]
    images = {}
    for spp in config.spp:  # methods interleaved, as in the pbrt protocol
        for seed in seeds:
            for method in config.methods:
                say(f"{method}: {spp} spp, seed {seed}")
                images[(method, spp, seed)] = render(scenes[method], params,
                                                     outdir / "renders" / f"{method}-{spp}-seed{seed}.exr",
                                                     spp, seed, variant)
    score(ev, name, spectrum.name, outdir, config, truth, images)
    return ev

