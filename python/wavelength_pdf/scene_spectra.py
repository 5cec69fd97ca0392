"""The emitter spectra a pbrt-v4 scene uses (design §3), one per distinct emitter.

``optimize scene.pbrt`` must produce exactly the tables a scene needs, so this module reads
the scene's statements (following ``Include`` and ``Import``) and collects every emitter:

- ``LightSource "type" ...`` (parameter ``L``, or ``I`` for point, spot and goniometric
  lights), and
- ``AreaLightSource "diffuse" ...`` (parameter ``L``) that is attached to at least one
  ``Shape`` in its attribute scope (an area light with no shape emits nothing).

An emitter's spectrum can be given, as documented for pbrt-v4, as

- ``"spectrum L" [ lambda value ... ]``  -- inline pairs, nm, piecewise linear;
- ``"spectrum L" "file.spd"``            -- a file of pairs (relative to the scene file that
  names it, or else to the top-level scene's folder);
- ``"spectrum L" "stdillum-D65"``        -- a named spectrum: ``stdillum-A``, ``-D50``,
  ``-D65``, ``-F1`` .. ``-F12`` and ``illum-acesD60`` (from colour-science's tables);
- ``"blackbody L" [ T ]``                -- Planck's law at T kelvin (``colour.sd_blackbody``);
- no ``L``/``I`` at all                  -- the colour space's illuminant (D65 for srgb,
  rec2020 and dci-p3; ACES D60 for aces2065-1), as pbrt-v4 does.

``"rgb L"`` and image-driven emitters (``"string filename"`` on an infinite, diffuse or
projection light) are not lamp spectra: they are reported, with file and line, as not
optimizable. ``Attribute "light" ...`` defaults are honoured within their attribute scope.

Spectra that differ only by a positive factor are the same emitter for the optimizer (the
objective is scale invariant and pbrt-v4 normalizes emitters to 1 nit), so they are
merged. The parsing is written here because no maintained Python package reads pbrt-v4
scenes; it is a tokenizer plus a walk over statements, not a scene builder.
"""

from __future__ import annotations

import os
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from wavelength_pdf.emitters import emission_parameter
from wavelength_pdf.files import InputFileError, read_regular_file
from wavelength_pdf.pbrt_syntax import Param, Statement, Token, split_params, statements, tokenize  # noqa: F401,E501
from wavelength_pdf.spectra import (
    Spectrum,
    SpectrumError,
    check_support,
    make_spectrum,
    read_spd,
)

__all__ = [
    "Token",
    "Emitter",
    "NotOptimizableWarning",
    "tokenize",
    "statements",
    "split_params",
    "scan_scene",
    "scene_spectra",
    "select_emitter",
    "read_scene",
    "whole_scene_spectrum",
    "named_spectrum",
    "NAMED_SPECTRA",
]

#: pbrt-v4's documented named illuminant spectra -> colour-science illuminant names.
#: ``illum-acesD60`` is the ACES white, a CIE daylight at ~6000 K: colour's D60.
NAMED_SPECTRA: dict[str, str] = {
    "stdillum-A": "A",
    "stdillum-D50": "D50",
    "stdillum-D65": "D65",
    **{f"stdillum-F{i}": f"FL{i}" for i in range(1, 13)},
    "illum-acesD60": "D60",
}

#: Illuminant of each pbrt-v4 colour space (the spectrum of an emitter given no L or I).
COLOR_SPACE_ILLUMINANT: dict[str, str] = {
    "srgb": "stdillum-D65",
    "rec2020": "stdillum-D65",
    "dci-p3": "stdillum-D65",
    "aces2065-1": "illum-acesD60",
}

#: Wavelength samples for blackbody emitters, nm: 1 nm steps (piecewise-linear error of
#: Planck's law at 1 nm is below 1e-5 relative) over a range wider than any table's.
BLACKBODY_RANGE = (300.0, 1000.0, 1.0)

#: Second radiation constant h c / k_B, m K, from the exact SI 2019 values of h, c and k_B
#: (colour-science defaults to the rounded 1.4388e-2 of ITS-90; pbrt-v4 uses h, c, k_B).
PLANCK_C2 = 6.62607015e-34 * 299792458.0 / 1.380649e-23



class NotOptimizableWarning(UserWarning):
    """An emitter that has no lamp spectrum (RGB colour or image) and gets no table."""


@dataclass
class Emitter:
    """One emitter statement of a scene.

    Attributes
    ----------
    statement : str
        ``LightSource "point"``-style description.
    where : str
        ``path:line`` of the statement.
    spectrum : Spectrum or None
        Its spectrum, or None when it has none (RGB or image emission).
    reason : str
        Why ``spectrum`` is None (empty otherwise).
    """

    statement: str
    where: str
    spectrum: Spectrum | None
    reason: str = ""


def named_spectrum(name: str, where: str) -> Spectrum:
    """A pbrt-v4 named illuminant spectrum (``stdillum-D65`` ...) from colour-science."""
    import colour

    key = NAMED_SPECTRA.get(name)
    if key is None:
        raise SpectrumError(f"{where}: unknown named spectrum {name!r} for an emitter; "
                            f"known: {', '.join(NAMED_SPECTRA)}")
    sd = colour.SDS_ILLUMINANTS[key]
    return make_spectrum(name, where, np.array(sd.wavelengths), np.array(sd.values))


def _blackbody(values: list[Token], where: str) -> Spectrum:
    import colour

    if len(values) != 1 or values[0].kind != "num":
        raise SpectrumError(f"{where}: \"blackbody\" takes one temperature in kelvin "
                            f"(pbrt-v4), got {len(values)} values")
    t = float(values[0].text)
    if not (np.isfinite(t) and t > 0):
        raise SpectrumError(f"{where}: blackbody temperature must be positive, got {t!r}")
    lo, hi, step = BLACKBODY_RANGE
    sd = colour.sd_blackbody(t, colour.SpectralShape(lo, hi, step), c2=PLANCK_C2)
    vals = np.array(sd.values)
    vals = vals / vals.max() if vals.max() > 0 else vals  # pbrt-v4 normalizes to peak 1
    return make_spectrum(f"blackbody-{t:g}K", where, np.array(sd.wavelengths), vals)


def _resolve(name: str, including: Path, top: Path) -> Path:
    """A path named in a scene file: relative to that file, else to the top-level scene."""
    p = Path(name)
    if p.is_absolute():
        return p
    for base in (including.parent, top.parent):
        if (base / p).exists():
            return Path(os.path.normpath(base / p))
    return Path(os.path.normpath(including.parent / p))


def _param_spectrum(param: Param, path: Path, top: Path) -> tuple[Spectrum | None, str]:
    """The spectrum of an emitter parameter, or (None, reason) when it has none."""
    where = param.where
    if param.type == "rgb":
        return None, f"{where}: \"rgb {param.name}\" is an RGB colour, not a lamp spectrum"
    if param.type == "blackbody":
        return _blackbody(param.values, where), ""
    if param.type != "spectrum":
        raise SpectrumError(f"{where}: parameter \"{param.type} {param.name}\" of an emitter "
                            f"must be spectrum, blackbody or rgb")
    vals = param.values
    if len(vals) == 1 and vals[0].kind == "str":
        name = vals[0].text
        if name in NAMED_SPECTRA:
            return named_spectrum(name, where), ""
        file = _resolve(name, path, top)
        if not file.exists():
            raise SpectrumError(f"{where}: spectrum {name!r} is neither a named spectrum nor "
                                f"a file (looked for {file})")
        try:
            sp = _read_spd_any(file)
        except SpectrumError as e:
            raise SpectrumError(f"{e} (named at {where})") from None
        return sp, ""
    for t in vals:
        if t.kind != "num":
            raise SpectrumError(f"{t.where}: cannot parse number {t.text!r} in "
                                f"\"spectrum {param.name}\"")
    if len(vals) % 2 or len(vals) < 4:
        raise SpectrumError(f"{where}: \"spectrum {param.name}\" needs (lambda, value) pairs, "
                            f"at least 2, got {len(vals)} numbers")
    nums = [float(t.text) for t in vals]
    lines = [t.line for t in vals[0::2]]
    sp = make_spectrum(f"{_label(top)}-line{param.values[0].line}", where, nums[0::2], nums[1::2],
                       where=str(param.values[0].path), lines=lines)
    return sp, ""


def _label(top: Path) -> str:
    """Short name of a scene: its file stem, or its folder for generic stems (scene-v4)."""
    stem = top.stem
    if stem.lower().startswith("scene") and top.resolve().parent.name:
        return top.resolve().parent.name
    return stem


def _read_spd_any(file: Path) -> Spectrum:
    """A .spd file read without the range check (done later, for the range of the table)."""
    return read_spd(file, lo=None, hi=None)


# --------------------------------------------------------------------------------------
# Walking a scene
# --------------------------------------------------------------------------------------

def _read_scene_text(path: Path, where: str | None) -> str:
    """A scene file's text: a regular file (as the renderer reads it, design §5.5; no size
    cap), so that a device or FIFO named as a scene or an Include fails at once."""
    try:
        data = read_regular_file(path, "scene", max_bytes=None)
    except InputFileError as e:
        if e.reason == "no such file":
            raise SpectrumError(f"{where or path}: no such file{f' ({path})' if where else ''}") from None
        if e.reason.startswith("is a directory"):
            raise SpectrumError(f"{where or path}: {path} is a directory, not a scene") from None
        raise SpectrumError(f"{where or path}: {path}: {e.reason}") from None
    return data.decode("utf-8-sig", errors="replace")


def scan_scene(path: str | Path) -> list[Emitter]:
    """Every emitter statement of a pbrt-v4 scene, in file order (Includes expanded).

    Raises
    ------
    SpectrumError
        Missing or unreadable files, syntax errors, bad emitter parameters.
    """
    top = Path(path)
    # Every emitter statement with a flag: is it used? (an area light needs a Shape)
    found: list[list] = []
    # Graphics state that matters here: the active area light (an index into ``found``),
    # "light" attribute defaults and the colour space; saved by AttributeBegin.
    state: dict = {"area": None, "light_defaults": [], "colorspace": "srgb"}
    stack: list[dict] = []

    def emitter(st: Statement, kind: str) -> Emitter:
        type_ = st.args[0].text
        desc = f'{kind} "{type_}"'
        where = st.directive.where
        params = {p.name: p for p in state["light_defaults"]}
        params.update({p.name: p for p in st.params})
        if "filename" in params and type_ in ("infinite", "diffuse", "projection"):
            image = params["filename"].values[0].text if params["filename"].values else "?"
            return Emitter(desc, where, None,
                           f"{where}: {desc} takes its emission from an image ({image}), "
                           f"not a lamp spectrum")
        pname = emission_parameter(kind, type_)
        param = params.get(pname)
        if param is None:
            illum = COLOR_SPACE_ILLUMINANT.get(state["colorspace"], "stdillum-D65")
            return Emitter(desc, where, named_spectrum(illum, where))
        sp, reason = _param_spectrum(param, param.decl.path, top)
        return Emitter(desc, where, sp, reason)

    def walk(file: Path, where: str | None, depth: int) -> None:
        if depth > 32:
            raise SpectrumError(f"{where}: Include nesting deeper than 32 (a cycle?)")
        text = _read_scene_text(file, where)
        for st in statements(tokenize(text, file)):
            d = st.directive.text
            if d in ("Include", "Import"):
                name = st.first_string()
                if name is None:
                    raise SpectrumError(f"{st.directive.where}: {d} needs a file name")
                walk(_resolve(name, file, top), st.directive.where, depth + 1)
            elif d == "AttributeBegin":
                stack.append(dict(state))
            elif d == "AttributeEnd":
                if not stack:
                    raise SpectrumError(f"{st.directive.where}: AttributeEnd without "
                                        f"AttributeBegin")
                state.update(stack.pop())
            elif d == "Attribute":
                if st.first_string() == "light":
                    split_params(st, 1)
                    state["light_defaults"] = state["light_defaults"] + st.params
            elif d == "ColorSpace":
                if st.first_string() is not None:
                    state["colorspace"] = st.first_string()
            elif d == "LightSource":
                found.append([emitter(split_params(st, 1), "LightSource"), True])
            elif d == "AreaLightSource":
                found.append([emitter(split_params(st, 1), "AreaLightSource"), False])
                state["area"] = len(found) - 1
            elif d == "Shape" and state["area"] is not None:
                found[state["area"]][1] = True

    walk(top, None, 0)
    return [em for em, used in found if used]


def _same_up_to_scale(a: Spectrum, b: Spectrum) -> bool:
    if a.wavelengths.shape != b.wavelengths.shape or not np.array_equal(a.wavelengths, b.wavelengths):
        return False
    sa, sb = a.values.max(), b.values.max()
    if sa == 0 or sb == 0:
        return sa == sb
    return bool(np.allclose(a.values / sa, b.values / sb, rtol=1e-12, atol=0))


def scene_spectra(path: str | Path, lo: float = 380.0, hi: float = 780.0) -> list[Spectrum]:
    """The distinct emitter spectra of a pbrt-v4 scene, in order of first use.

    Emitters without a lamp spectrum (RGB, images) are skipped with a
    :class:`NotOptimizableWarning` naming file and line.

    Raises
    ------
    SpectrumError
        No emitter with a lamp spectrum, a spectrum with no energy in ``[lo, hi]`` nm,
        or any reading error.
    """
    emitters = scan_scene(path)
    if not emitters:
        raise SpectrumError(f"{path}: the scene has no emitters (LightSource or "
                            f"AreaLightSource with a Shape)")
    distinct: list[Spectrum] = []
    users: list[int] = []
    for em in emitters:
        if em.spectrum is None:
            continue
        check_support(em.spectrum, lo, hi, where=em.where)
        for i, sp in enumerate(distinct):
            if _same_up_to_scale(sp, em.spectrum):
                users[i] += 1
                break
        else:
            distinct.append(em.spectrum)
            users.append(1)
    skipped = [em for em in emitters if em.spectrum is None]
    if not distinct:
        raise SpectrumError(f"{skipped[0].reason}: no emitter of the scene has a lamp "
                            f"spectrum to optimize")
    for em in skipped:
        warnings.warn(f"{em.reason}: not optimizable, no table for it", NotOptimizableWarning,
                      stacklevel=2)
    # Unique names (used to pick an emitter and to name output tables).
    named: list[Spectrum] = []
    seen: dict[str, int] = {}
    for sp in distinct:
        n = seen.get(sp.name, 0)
        seen[sp.name] = n + 1
        name = sp.name if n == 0 else f"{sp.name}-{n + 1}"
        named.append(Spectrum(name=name, source=sp.source, wavelengths=sp.wavelengths,
                              values=sp.values))
    return named


def read_scene(path: str | Path, selector: str | None, lo: float = 380.0,
               hi: float = 780.0) -> list[Spectrum]:
    """The reader ``spectra.load_spectra`` uses for ``.pbrt``: the scene's emitter spectra,
    or the one ``selector`` (``N`` or ``NAME``) picks."""
    sps = scene_spectra(path, lo=lo, hi=hi)
    return sps if selector is None else [select_emitter(sps, selector, path)]


def select_emitter(spectra: list[Spectrum], selector: str, scene: str | Path) -> Spectrum:
    """Pick one spectrum of a scene by index (from 0) or by name."""
    if selector.strip().lstrip("-").isdigit():
        i = int(selector)
        if 0 <= i < len(spectra):
            return spectra[i]
    else:
        for sp in spectra:
            if sp.name == selector:
                return sp
    listing = "; ".join(f"#{i}: {s.name} ({s.source})" for i, s in enumerate(spectra))
    raise SpectrumError(f"{scene}: no emitter {selector!r}; the scene has {listing}")


@contextmanager
def renderer_output(scene: Path, flag: str, filename: str, what: str,
                    pbrt: str | os.PathLike | None = None) -> Iterator[Path]:
    """Run ``pbrt --quiet FLAG OUT SCENE`` (the renderer found as the evaluation finds it,
    design §7) and yield OUT, a file in a temporary folder removed afterwards; the
    renderer's refusal becomes a :class:`SpectrumError` with its message (file and line)."""
    import subprocess
    import tempfile

    from wavelength_pdf.renderer import find_pbrt

    if not scene.is_file():
        raise SpectrumError(f"{scene}: no such scene file" if not scene.exists()
                            else f"{scene}: not a file")
    binary = find_pbrt(pbrt)
    with tempfile.TemporaryDirectory(prefix="wavelength-pdf-") as tmp:
        out = Path(tmp) / filename
        proc = subprocess.run([str(binary), "--quiet", flag, str(out), str(scene)],
                              capture_output=True, text=True)
        if proc.returncode != 0 or not out.is_file():
            msg = " ".join(line.removeprefix("pbrt: ") for line in proc.stderr.splitlines()
                           if line.strip() and "warning:" not in line)
            raise SpectrumError(f"{scene}: the renderer ({binary}) cannot give the scene's "
                                f"{what}: {msg or f'exit status {proc.returncode}'}")
        yield out


def whole_scene_spectrum(path: str | Path, lo: float = 380.0, hi: float = 780.0,
                         pbrt: str | os.PathLike | None = None) -> Spectrum:
    """The scene's total emitted spectral power, the renderer's own account of it.

    Runs ``pbrt --emission-spectrum`` (design §5.6): every light's spectrum weighted by the
    power it emits in that scene (area, scale, two-sidedness, transforms, pbrt-v4's light
    power), summed. The renderer is the authority here because only it builds the scene
    (areas after transforms, per-triangle ``power``, RGB and blackbody emission, the scene
    radius of infinite lights); this module only reads statements. The renderer is found as
    the evaluation finds it (``pbrt``, else ``$WAVELENGTH_PDF_PBRT``, else the checkout's
    ``build/pbrt``, else the installed wheel's own, else ``pbrt`` on ``PATH``; design §7).

    Raises
    ------
    SpectrumError
        The scene is missing, the renderer refuses it (a scene with no emitters, a syntax
        error: its message, naming file and line), or the total has no energy in
        ``[lo, hi]``.
    wavelength_pdf.renderer.RendererNotFound
        No renderer.
    """
    scene = Path(path)
    with renderer_output(scene, "--emission-spectrum", f"{_label(scene)}-whole-scene.spd",
                         "emission", pbrt) as out:
        sp = read_spd(out, lo=None, hi=None)
    sp = Spectrum(name=f"{_label(scene)}-whole-scene", source=f"{scene} (all emitters, "
                  f"weighted by power: pbrt --emission-spectrum)", wavelengths=sp.wavelengths,
                  values=sp.values)
    check_support(sp, lo, hi, where=str(scene))
    return sp
