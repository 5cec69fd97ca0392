"""Emission-stratified wavelength sampling for a Mitsuba 3 scene: no table file (design §1.7, §8.3).

``emission_srf(scene)`` gives a sensor's ``srf``: the ``wavelength_table`` texture on the table
that the renderer's ``--wavelength-sampling emission`` would build, computed from the scene's own
emitters. Their emitted spectral power is summed as pbrt-v4 sums light power (design §5.6),

    Phi(lambda) = sum over emitters of k * L(lambda),

with k = pi A for an area emitter (one-sided, A its area in world space), 4 pi for a point light,
2 pi (1 - (sin c - sin b) / (c - b)) for a spot light (Mitsuba's falloff is linear in angle from
the beam width b to the cutoff c; 2 pi (1 - cos c) when they are equal), pi r^2 for a directional
emitter and 4 pi^2 r^2 for the constant and environment emitters (r the radius of the sphere
bounding the scene). Phi is multiplied by the weight (``spd``: 1; ``luminance``: ybar; ``xyz``:
xbar + ybar + zbar) and cut into four equal-mass densities by ``wavelength_pdf.stratified``
on 360-830 nm, the range Mitsuba's spectral variants sample.

Spectra are taken as Mitsuba evaluates them, at the union of the emitters' own nodes (irregular
and regular spectra: exact, they are linear between them) and every nanometre of 360-830 nm
(blackbody, RGB and other smooth spectra). An emitter whose radiance is an RGB image (an
``envmap``, or an area emitter with a bitmap ``radiance``) counts as its colour space's
illuminant (Mitsuba's D65) times its average power, measured at four wavelengths over the
image (exact for a grey image): an image has no single spectrum.
"""
from __future__ import annotations

import hashlib
import math

import numpy as np

from wavelength_pdf.spectra import Spectrum
from wavelength_pdf.stratified import WEIGHTS, StratifiedError, stratified_table
from wavelength_pdf.table import Table, format_table

__all__ = ["LAMBDA_RANGE", "DEFAULT_WEIGHT", "EmissionError", "emitted_power", "emission_table",
           "emission_srf", "registered_table"]

#: The range Mitsuba's spectral variants sample (MI_CIE_MIN, MI_CIE_MAX), nm.
LAMBDA_RANGE = (360.0, 830.0)
#: The weight unless one is given (the renderer's --emission-weight default).
DEFAULT_WEIGHT = "spd"
#: Wavelengths at which an image emitter's power is measured against the illuminant.
_PROBE = (450.0, 510.0, 570.0, 630.0)
#: Cells a side of the grid over which an image is averaged (uv for area emitters; for an
#: environment, this many rows in theta and twice as many columns in phi).
_IMAGE_GRID = 32

_TABLES: dict[str, Table] = {}


class EmissionError(ValueError):
    """A scene whose emission cannot be sampled (the message names the emitter and why)."""


def registered_table(key: str) -> Table:
    """The table ``emission_srf`` registered under ``key`` (the texture's ``table`` property)."""
    try:
        return _TABLES[key]
    except KeyError:
        raise EmissionError(f"no emission table {key!r} in this process (emission_srf registers "
                            "it; a table file goes in the 'filename' property)") from None


def _mi():
    import mitsuba as mi

    variant = mi.variant() or ""
    if "spectral" not in variant:
        raise EmissionError(f"emission sampling needs a spectral variant, not {variant!r}")
    return mi


def _scalar(x) -> float:
    """A Python float from a Mitsuba scalar or a JIT array of one value."""
    return float(np.asarray(x, dtype=np.float64).ravel()[0])


def _name(emitter) -> str:
    ident = emitter.id() if hasattr(emitter, "id") else ""
    kind = emitter.class_name()
    return f"emitter {ident!r} ({kind})" if ident else f"an emitter ({kind})"


def _params(mi, emitter) -> dict:
    p = mi.traverse(emitter)
    return {k: p[k] for k in p.keys()}


def _spectrum_nodes(params: dict, prefix: str) -> np.ndarray | None:
    """The nodes of a tabulated spectrum parameter (irregular or regular), else None."""
    if f"{prefix}.wavelengths" in params:
        return np.asarray(params[f"{prefix}.wavelengths"], dtype=np.float64).ravel()
    if f"{prefix}.range" in params and f"{prefix}.values" in params:
        lo, hi = np.asarray(params[f"{prefix}.range"], dtype=np.float64).ravel()[:2]
        n = np.asarray(params[f"{prefix}.values"]).size
        return np.linspace(lo, hi, n)
    return None


def _is_image(params: dict, prefix: str) -> bool:
    """Whether the spectrum parameter is a bitmap (RGB image) texture."""
    return any(k.startswith(prefix + ".") and k.endswith("data") for k in params)


def _evaluate(mi, lam: np.ndarray, fn, width: int = 1) -> np.ndarray:
    """fn(wavelengths) -> spectrum (4 lanes of ``width`` values each) at every lam, as
    (lam.size, width). JIT variants evaluate all wavelengths in one call (width x batches
    lanes); scalar variants call once per batch of four."""
    n = -(-lam.size // 4)
    pad = np.concatenate([lam, np.full(n * 4 - lam.size, lam[-1])]).reshape(n, 4)
    jit = not mi.variant().startswith("scalar")
    if jit:
        wl = [mi.Float(np.repeat(pad[:, j], width)) for j in range(4)]
        out = fn(wl, n * width)

        def lane(j):  # a spectrum that does not depend on its inputs comes back as one value
            v = np.asarray(out[j], dtype=np.float64).ravel()
            return np.full(n * width, v[0]) if v.size == 1 else v

        vals = np.stack([lane(j).reshape(n, width) for j in range(4)], axis=1)
        return vals.reshape(n * 4, width)[: lam.size]
    rows = []
    for b in range(n):
        per = []
        for w in range(width):
            out = fn([float(v) for v in pad[b]], 1, w)
            per.append([float(out[j]) for j in range(4)])
        rows.append(np.array(per).T)  # (4, width)
    return np.concatenate(rows, axis=0)[: lam.size]


def _zeros(mi, cls, width):
    import drjit as dr

    return dr.zeros(cls) if mi.variant().startswith("scalar") else dr.zeros(cls, width)


def _si(mi, wl, width, wi=(0.0, 0.0, 1.0), uv=None):
    si = _zeros(mi, mi.SurfaceInteraction3f, width)
    si.wavelengths = type(si.wavelengths)(*wl)
    si.wi = mi.Vector3f(*wi)
    if uv is not None:
        si.uv = mi.Point2f(*uv)
    return si


def _interaction(mi, wl, width, p):
    it = _zeros(mi, mi.Interaction3f, width)
    it.wavelengths = type(it.wavelengths)(*wl)
    it.p = mi.Point3f(*(float(v) for v in p))
    return it


def _grid_uv(n: int) -> tuple[np.ndarray, np.ndarray]:
    c = (np.arange(n) + 0.5) / n
    u, v = np.meshgrid(c, c, indexing="ij")
    return u.ravel(), v.ravel()


def _radiance_area(mi, e, lam, image: bool):
    """L(lambda) of an area emitter (the mean over uv of an image's)."""
    if not image:
        return _evaluate(mi, lam, lambda wl, w, *_: e.eval(_si(mi, wl, w, uv=(0.5, 0.5))))[:, 0]
    u, v = _grid_uv(_IMAGE_GRID)
    k = u.size
    jit = not mi.variant().startswith("scalar")

    def fn(wl, w, cell=None):
        if jit:
            reps = w // k
            return e.eval(_si(mi, wl, w, uv=(mi.Float(np.tile(u, reps)), mi.Float(np.tile(v, reps)))))
        return e.eval(_si(mi, wl, 1, uv=(float(u[cell]), float(v[cell]))))

    return _evaluate(mi, lam, fn, width=k).mean(axis=1)


def _radiance_environment(mi, e, lam):
    """The radiance of an environment emitter averaged over the sphere (solid-angle weights)."""
    rows = _IMAGE_GRID
    theta = (np.arange(rows) + 0.5) * math.pi / rows
    phi = (np.arange(2 * rows) + 0.5) * math.pi / rows
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    w = np.sin(t).ravel()
    w = w / w.sum()
    k = d.shape[0]
    jit = not mi.variant().startswith("scalar")

    def fn(wl, width, cell=None):
        if jit:
            reps = width // k
            wi = tuple(mi.Float(np.tile(d[:, c], reps)) for c in range(3))
            return e.eval(_si(mi, wl, width, wi=wi))
        return e.eval(_si(mi, wl, 1, wi=tuple(float(x) for x in d[cell])))

    return _evaluate(mi, lam, fn, width=k) @ w


def _image_as_illuminant(mi, radiance_at, lam):
    """An image emitter as D65 (Mitsuba's illuminant of RGB emission) times its power
    relative to it, measured at the _PROBE wavelengths."""
    d65 = mi.load_dict({"type": "d65"})
    probe = np.array(_PROBE)
    shape = lambda x: _evaluate(mi, x, lambda wl, w, *_: d65.eval(_si(mi, wl, w)))[:, 0]  # noqa: E731
    power = float(np.sum(radiance_at(probe)) / np.sum(shape(probe)))
    return power * shape(lam)


def _spot_factor(params: dict) -> float:
    c = math.radians(_scalar(params["cutoff_angle"]))
    b = math.radians(_scalar(params["beam_width"]))
    if c - b <= 1e-9:
        return 2 * math.pi * (1 - math.cos(c))
    return 2 * math.pi * (1 - (math.sin(c) - math.sin(b)) / (c - b))


def _transform_point(mi, params: dict, local) -> tuple[float, float, float]:
    m = np.asarray(params["to_world"].matrix, dtype=np.float64).reshape(4, 4)
    q = m @ np.array([*local, 1.0])
    return tuple(q[:3] / q[3])


def emitted_power(scene_or_emitters, radius: float | None = None) -> Spectrum:
    """The total emitted spectral power of a Mitsuba scene's emitters on 360-830 nm.

    Parameters
    ----------
    scene_or_emitters : mitsuba.Scene or sequence of mitsuba.Emitter
        A loaded scene (in the current spectral variant), or emitters.
    radius : float, optional
        The radius of the sphere bounding the scene, for directional, constant and
        environment emitters when emitters rather than a scene are given.

    Raises
    ------
    EmissionError
        No emitters, an emitter type this function does not know, an emitter whose power is
        not finite or negative (named), or emitters that emit nothing in 360-830 nm.
    """
    mi = _mi()
    if isinstance(scene_or_emitters, mi.Scene):
        emitters = list(scene_or_emitters.emitters())
        if radius is None:
            radius = _scalar(scene_or_emitters.bbox().bounding_sphere().radius)
    else:
        emitters = list(scene_or_emitters)
    if not emitters:
        raise EmissionError("the scene has no emitters, so it emits no spectral power")
    lo, hi = LAMBDA_RANGE
    params = [_params(mi, e) for e in emitters]
    # Nodes: every emitter's tabulated nodes, and the nanometres for everything else.
    nodes = [np.array([lo, hi])]
    for e, p in zip(emitters, params):
        prefix = {"PointLight": "intensity", "SpotLight": "intensity",
                  "DirectionalEmitter": "irradiance"}.get(e.class_name(), "radiance")
        own = _spectrum_nodes(p, prefix)
        nodes.append(np.arange(lo, hi + 0.5, 1.0) if own is None else own)
    lam = np.unique(np.concatenate(nodes))
    lam = lam[(lam >= lo) & (lam <= hi)]

    total = np.zeros(lam.size)
    for e, p in zip(emitters, params):
        kind, who = e.class_name(), _name(e)
        if kind == "AreaLight":
            shape = e.get_shape()
            k = math.pi * _scalar(shape.surface_area())
            if _is_image(p, "radiance"):
                L = _image_as_illuminant(mi, lambda x: _radiance_area(mi, e, x, True), lam)
            else:
                L = _radiance_area(mi, e, lam, False)
        elif kind in ("PointLight", "SpotLight"):
            if kind == "PointLight":
                pos = tuple(float(v) for v in np.asarray(p["position"]).ravel()[:3])
                at, k = (pos[0] + 1.0, pos[1], pos[2]), 4 * math.pi
            else:
                at, k = _transform_point(mi, p, (0.0, 0.0, 1.0)), _spot_factor(p)
            L = _evaluate(mi, lam, lambda wl, w, *_: e.sample_direction(
                _interaction(mi, wl, w, at), mi.Point2f(0.5, 0.5))[1])[:, 0]
        elif kind == "DirectionalEmitter":
            if radius is None:
                raise EmissionError(f"{who}: a directional emitter's power needs the scene's radius")
            k = math.pi * radius ** 2
            L = _evaluate(mi, lam, lambda wl, w, *_: e.sample_direction(
                _interaction(mi, wl, w, (0.0, 0.0, 0.0)), mi.Point2f(0.5, 0.5))[1])[:, 0]
        elif kind in ("ConstantBackgroundEmitter", "EnvironmentMapEmitter"):
            if radius is None:
                raise EmissionError(f"{who}: an environment's power needs the scene's radius")
            k = 4 * math.pi ** 2 * radius ** 2
            if kind == "EnvironmentMapEmitter":
                L = _image_as_illuminant(mi, lambda x: _radiance_environment(mi, e, x), lam)
            else:
                L = _evaluate(mi, lam, lambda wl, w, *_: e.eval(_si(mi, wl, w)))[:, 0]
        else:
            raise EmissionError(f"{who}: emission sampling does not know this emitter type; "
                                "give the sensor a table instead (wavelength_table 'filename')")
        contribution = k * np.asarray(L, dtype=np.float64)
        if not np.all(np.isfinite(contribution)) or np.any(contribution < 0):
            bad = lam[~(np.isfinite(contribution) & (contribution >= 0))][0]
            raise EmissionError(f"{who}: its emitted power is not finite and non-negative at "
                                f"{bad:g} nm (a blackbody of 0 K, an overflowing scale?)")
        total = total + contribution
    if not np.all(np.isfinite(total)):
        raise EmissionError("the scene's total emitted power overflows")
    if not np.any(total > 0):
        raise EmissionError(f"no emitter of the scene emits between {lo:g} and {hi:g} nm "
                            f"({_name(emitters[0])} and every other has zero power)")
    return Spectrum("mitsuba-scene-emission", "the scene's emitters, weighted by power "
                    "(wavelength_pdf.mitsuba.emitted_power)", lam, total)


def emission_table(scene_or_emitters, weight: str = DEFAULT_WEIGHT, radius: float | None = None) -> Table:
    """The table emission sampling uses for a Mitsuba scene: ``emitted_power`` times the
    weight, four equal-mass bands on 360-830 nm (``wavelength_pdf.stratified``)."""
    if weight not in WEIGHTS:
        raise EmissionError(f"unknown weight {weight!r}; choose from {', '.join(WEIGHTS)}")
    phi = emitted_power(scene_or_emitters, radius)
    try:
        return stratified_table(phi, weight, *LAMBDA_RANGE)
    except StratifiedError as e:
        raise EmissionError(f"the scene's emission: {e}") from None


def emission_srf(scene_or_emitters, weight: str = DEFAULT_WEIGHT, radius: float | None = None) -> dict:
    """A sensor ``srf`` (a scene-dict entry) that samples wavelengths by the scene's emission.

    Usage (any spectral variant; ``wavelength_pdf.mitsuba.register()`` first)::

        scene_dict["sensor"]["srf"] = wpm.emission_srf(mi.load_dict(scene_dict))
        scene = mi.load_dict(scene_dict)

    The table lives in this process (the texture's ``table`` property names it); to keep it,
    ``write_table(path, emission_table(scene))`` and use ``filename`` instead.
    """
    table = emission_table(scene_or_emitters, weight, radius)
    key = "emission-" + hashlib.sha256(format_table(table).encode()).hexdigest()[:20]
    _TABLES[key] = table
    return {"type": "wavelength_table", "table": key}
