"""A copy of a pbrt-v4 scene lit by another spectrum, for the evaluation (design §6).

The copy is written elsewhere (../shared is read-only), so every file the scene names
(Include/Import, meshes, textures, spectrum files) is rewritten to an absolute path. Every
emitter's ``L``/``I`` (spectrum, rgb or blackbody) becomes the given spectrum, inline and cut to
the evaluation's wavelength range, so that every sampler of the comparison integrates the same
thing; its "scale" is kept (pbrt-v4 normalizes the spectrum to 1 nit before scaling it). The
film's resolution can be overridden, or scaled by a factor, to fit a small machine.

Statements are found with the optimizer's own pbrt tokenizer (``scene_spectra``); only the
spans of the tokens that change are replaced, so everything else stays byte for byte.
"""
from __future__ import annotations

from pathlib import Path
from typing import Collection

import numpy as np

from wavelength_pdf.emitters import emission_parameter
from wavelength_pdf.pbrt_syntax import Token, split_params, statements, tokenize
from wavelength_pdf.spectra import Spectrum, SpectrumError

#: Parameters whose string value names a file, relative to the file that names it.
_FILE_PARAMS = {"filename", "mapname", "lensfile", "bsdffile"}
#: pbrt-v4's film size when the scene gives none.
DEFAULT_FILM = (1280, 720)
#: Directives with a parameter list, and how many quoted arguments come before it.
_WITH_PARAMS = {d: 1 for d in ("Shape", "LightSource", "AreaLightSource", "Material", "MakeNamedMaterial",
                               "Film", "Camera", "Sampler", "Integrator", "PixelFilter", "Accelerator",
                               "MakeNamedMedium", "Attribute")}
_WITH_PARAMS["Texture"] = 3


#: Values below this fraction of the peak are written as 0 into a scene (design §3.3).
SCENE_FLOOR = 1e-30
#: pbrt-v4 extends a spectrum beyond its first and last samples with their values; a cut
#: spectrum ends with a zero this far outside [lo, hi], nm, so that it emits nothing there.
CUT_STEP = 1e-3


def inline_spectrum(spectrum: Spectrum, lo: float, hi: float) -> str:
    """``[ lambda value ... ]`` of a spectrum cut to [lo, hi] (exact at lo and hi, and 0 from
    ``CUT_STEP`` outside them on: pbrt-v4 would extend the end values over its whole range)."""
    lam = spectrum.wavelengths
    inside = (lam > lo) & (lam < hi)
    grid = np.concatenate([[lo], lam[inside], [hi]])
    values = np.interp(grid, lam, spectrum.values, left=0.0, right=0.0)
    if not np.any(values > 0):
        raise SpectrumError(f"{spectrum.source}: no energy inside {lo:g}-{hi:g} nm")
    # The renderer reads single precision: values below 1e-30 of the peak (a Gaussian line's
    # far tails) would underflow there, and change nothing (design §3.3).
    values = np.where(values < values.max() * SCENE_FLOOR, 0.0, values)
    if values[0] > 0:
        grid, values = np.concatenate([[lo - CUT_STEP], grid]), np.concatenate([[0.0], values])
    if values[-1] > 0:
        grid, values = np.concatenate([grid, [hi + CUT_STEP]]), np.concatenate([values, [0.0]])
    return "[ " + " ".join(f"{w:.10g} {v:.10g}" for w, v in zip(grid, values)) + " ]"


def _scaled(pixels: float, factor: float) -> int:
    """A film size times ``factor``, rounded, at least 1."""
    if not (factor > 0 and np.isfinite(factor)):
        raise ValueError(f"resolution scale must be a positive number, got {factor!r}")
    return max(1, int(round(pixels * factor)))


def _span(tokens: list[Token]) -> tuple[int, int]:
    return tokens[0].start, tokens[-1].end


def edit_scene(scene: str | Path, spectrum: Spectrum | None, out: str | Path, *,
               lo: float = 380.0, hi: float = 780.0,
               resolution: tuple[int, int] | float | None = None,
               maxdepth: int | None = None, pixel_sampler: str | None = None,
               cut_emitters: bool = False, dark: Collection[tuple[str, int]] = ()) -> Path:
    """Write a copy of ``scene`` at ``out`` lit by ``spectrum`` (None: keep the emitters).

    ``resolution`` is the film's new (width, height), or a factor applied to the scene's own
    size (pbrt-v4's 1280x720 when it gives none; at least one pixel a side), or None to keep it.
    ``maxdepth`` replaces the integrator's "maxdepth" (added when it gives none); None keeps it.
    ``pixel_sampler`` (e.g. "independent") replaces the scene's ``Sampler`` statement by one of
    that type with the same "pixelsamples" (added before ``WorldBegin`` when there is none);
    None keeps it. ``cut_emitters`` (with ``spectrum`` None) cuts every emitter's inline
    spectrum to [lo, hi] as :func:`inline_spectrum` does, so that every sampler of the
    comparison integrates the same light; an emitter given otherwise (rgb, blackbody, a file)
    is an error then. ``dark`` names emitter statements by (file name, line) whose "scale"
    becomes 0 (added when they give none): a copy lit by some of the scene's lights only, with
    every light's geometry in place.

    Included files are inlined into the copy's folder as edited copies of their own, so that
    emitters and file names inside them are handled the same way.

    Returns
    -------
    Path
        ``out``.
    """
    scene, out = Path(scene).resolve(), Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    body = _edit_file(scene, spectrum, out.parent, lo, hi, resolution, maxdepth, depth=0,
                      pixel_sampler=pixel_sampler, cut=cut_emitters, dark=set(dark))
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(body)
    tmp.replace(out)
    return out


def _edit_file(path: Path, spectrum: Spectrum | None, outdir: Path, lo: float, hi: float,
               resolution: tuple[int, int] | float | None, maxdepth: int | None, depth: int,
               pixel_sampler: str | None = None, cut: bool = False, dark: set = frozenset()) -> str:
    if depth > 32:
        raise SpectrumError(f"{path}: Include nesting deeper than 32 (a cycle?)")
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        raise SpectrumError(f"{path}: cannot read ({e.strerror})") from None
    edits: list[tuple[int, int, str]] = []
    here = path.parent

    def absolute(tok: Token) -> None:
        p = Path(tok.text)
        if not p.is_absolute() and (here / p).exists():
            edits.append((tok.start, tok.end, '"' + str((here / p).resolve()) + '"'))

    sampler_seen = False
    for st in statements(tokenize(text, path)):
        d = st.directive.text
        if d == "WorldBegin" and pixel_sampler and depth == 0 and not sampler_seen:
            anchor = st.directive.start
            edits.append((anchor, anchor, f'Sampler "{pixel_sampler}"\n'))
            sampler_seen = True
        if d in ("Include", "Import") and st.items and isinstance(st.items[0], Token):
            arg = st.items[0]
            child = (here / arg.text).resolve()
            name = f"include-{depth + 1}-{abs(hash(str(child))) % 10**8}.pbrt"
            (outdir / name).write_text(_edit_file(child, spectrum, outdir, lo, hi, resolution, maxdepth,
                                                  depth + 1, pixel_sampler, cut, dark))
            edits.append((arg.start, arg.end, f'"{outdir / name}"'))
            continue
        if d not in _WITH_PARAMS:
            continue
        split_params(st, _WITH_PARAMS[d])
        type_ = st.args[0].text if st.args and st.args[0].kind == "str" else ""
        emitting = spectrum is not None and d in ("LightSource", "AreaLightSource")
        pname = emission_parameter(d, type_)
        replaced = False
        cutting = cut and spectrum is None and d in ("LightSource", "AreaLightSource")
        if cutting:
            _cut_emitter(st, text, pname, lo, hi, path, edits)
        for p in st.params:
            if cutting and p.name == pname:
                continue
            if emitting and p.name == pname and p.type in ("spectrum", "rgb", "blackbody"):
                start, end = p.decl.start, (p.values[-1].end if p.values else p.decl.end)
                # Include a closing bracket right after the last value.
                if text[end:].lstrip().startswith("]"):
                    end = text.index("]", end) + 1
                edits.append((start, end, f'"spectrum {pname}" {inline_spectrum(spectrum, lo, hi)}'))
                replaced = True
            elif d == "Film" and resolution and p.name in ("xresolution", "yresolution") and p.values:
                axis = 0 if p.name == "xresolution" else 1
                if isinstance(resolution, tuple):
                    value = resolution[axis]
                else:
                    try:
                        pixels = float(p.values[0].text)
                    except ValueError:
                        raise SpectrumError(f"{path}:{p.values[0].line}: {p.name} is not a number: "
                                            f"{p.values[0].text!r}") from None
                    value = _scaled(pixels, resolution)
                edits.append((*_span(p.values), str(value)))
            elif d == "Integrator" and maxdepth is not None and p.name == "maxdepth" and p.values:
                edits.append((*_span(p.values), str(int(maxdepth))))
            elif p.type == "string" and p.name in _FILE_PARAMS and p.values:
                absolute(p.values[0])
            elif p.type == "spectrum" and p.values and p.values[0].kind == "str":
                absolute(p.values[0])
        if d == "Sampler" and pixel_sampler:
            sampler_seen = True
            count = next((p.values[0].text for p in st.params if p.name == "pixelsamples" and p.values), None)
            last = st.items[-1] if st.items else st.directive
            end = (last[-1] if isinstance(last, list) and last else last).end
            if text[end:].lstrip().startswith("]"):
                end = text.index("]", end) + 1
            new = f'Sampler "{pixel_sampler}"' + (f' "integer pixelsamples" [ {count} ]' if count else "")
            edits.append((st.directive.start, end, new))
            continue
        if d in ("LightSource", "AreaLightSource") and (path.name, st.directive.line) in dark:
            scale = next((p for p in st.params if p.name == "scale" and p.values), None)
            if scale is not None:
                edits.append((*_span(scale.values), "0"))
            else:
                anchor = st.args[0].end if st.args else st.directive.end
                edits.append((anchor, anchor, ' "float scale" [ 0 ]'))
        if emitting and not replaced:
            # No L/I given (the colour space's illuminant): add the spectrum after the type.
            anchor = st.args[0].end if st.args else st.directive.end
            edits.append((anchor, anchor, f' "spectrum {pname}" {inline_spectrum(spectrum, lo, hi)}'))
        if d == "Film" and resolution:
            given = {p.name for p in st.params}
            size = resolution if isinstance(resolution, tuple) else \
                tuple(_scaled(v, resolution) for v in DEFAULT_FILM)
            anchor = st.args[0].end if st.args else st.directive.end
            added = "".join(f' "integer {name}" [ {size[axis]} ]'
                            for axis, name in enumerate(("xresolution", "yresolution")) if name not in given)
            if added:
                edits.append((anchor, anchor, added))
        if d == "Integrator" and maxdepth is not None and "maxdepth" not in {p.name for p in st.params}:
            anchor = st.args[0].end if st.args else st.directive.end
            edits.append((anchor, anchor, f' "integer maxdepth" [ {int(maxdepth)} ]'))
    for start, end, new in sorted(edits, key=lambda e: e[0], reverse=True):
        text = text[:start] + new + text[end:]
    return text


def _cut_emitter(st, text: str, pname: str, lo: float, hi: float, path: Path, edits: list) -> None:
    """Cut an emitter's inline ``spectrum L/I`` to [lo, hi] (``edit_scene(cut_emitters=True)``)."""
    from wavelength_pdf.spectra import make_spectrum

    for p in st.params:
        if p.name != pname:
            continue
        if p.type != "spectrum" or not p.values:
            raise SpectrumError(f"{path}:{st.directive.line}: an emitter's {p.type} {pname} cannot be cut to "
                                f"{lo:g}-{hi:g} nm (only a spectrum, inline or a file, can)")
        if p.values[0].kind == "str":
            from wavelength_pdf.spectra import read_spd

            file = (path.parent / p.values[0].text).resolve()
            if file.suffix.lower() != ".spd":
                raise SpectrumError(f"{path}:{st.directive.line}: the emitter's spectrum {p.values[0].text!r} "
                                    "is not a .spd file and cannot be cut")
            sp = read_spd(file, lo=None, hi=None)
        else:
            numbers = [float(v.text) for v in p.values]
            sp = make_spectrum("emitter", f"{path}:{st.directive.line}", numbers[0::2], numbers[1::2],
                               where=f"{path}:{st.directive.line}")
        # pbrt-v4 extends the end values beyond the samples: so does the cut, before cutting.
        lam, val = np.asarray(sp.wavelengths), np.asarray(sp.values)
        lam = np.concatenate([[min(lo, lam[0]) - 1.0], lam, [max(hi, lam[-1]) + 1.0]])
        val = np.concatenate([[val[0]], val, [val[-1]]])
        sp = make_spectrum("emitter", sp.source, lam, val)
        start, end = p.decl.start, p.values[-1].end
        if text[end:].lstrip().startswith("]"):
            end = text.index("]", end) + 1
        edits.append((start, end, f'"spectrum {pname}" {inline_spectrum(sp, lo, hi)}'))
        return
    raise SpectrumError(f"{path}:{st.directive.line}: an emitter without an inline spectrum {pname} cannot be "
                        f"cut to {lo:g}-{hi:g} nm")
