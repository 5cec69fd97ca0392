"""``wavelength-pdf mitsuba SCENE.xml``: render a Mitsuba 3 XML scene with the
``wavelength_table`` plugin registered (Mitsuba's own ``mitsuba`` command cannot load a plugin
written in Python). The flags are Mitsuba's: ``-m``, ``-o``, ``-D``, ``-s``, ``-a``, ``-t``; also
``python -m wavelength_pdf mitsuba``."""
from __future__ import annotations

import argparse
from pathlib import Path

from wavelength_pdf.cli import Formatter, positive_int


def _define(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    return key, value


#: The default variant (``wavelength_pdf.mitsuba.scenes.DEFAULT_VARIANT``; not imported here,
#: which would load Mitsuba for every ``--help``).
DEFAULT_VARIANT = "llvm_ad_spectral"


def cmd_mitsuba(args: argparse.Namespace) -> int:
    from wavelength_pdf.cli import BadInput

    try:
        from wavelength_pdf.mitsuba.scenes import render_file
    except ImportError as e:
        raise BadInput(f"Mitsuba 3 is not installed (the package's mitsuba extra): pip install mitsuba ({e})") from None

    paths = [p for group in args.append for p in group.split(";") if p]
    out = render_file(args.scene, args.output, variant=args.mode, spp=args.spp, sensor=args.sensor,
                      seed=args.seed, defines=dict(args.define), search_paths=paths, threads=args.threads)
    print(f"wrote {out}")
    return 0


def add_parser(sub) -> None:
    m = sub.add_parser(
        "mitsuba", formatter_class=Formatter,
        help="render a Mitsuba 3 XML scene that uses the wavelength_table plugin",
        description="Renders SCENE.xml with Mitsuba 3 and the wavelength_table plugin registered, "
                    "as Mitsuba's own command would (which cannot load a plugin written in Python: "
                    "it says 'Plugin \"wavelength_table\" not found'). In the scene, put <texture "
                    "type=\"wavelength_table\" name=\"srf\"><string name=\"filename\" "
                    "value=\"table.csv\"/></texture> in the <sensor>. Needs Mitsuba 3 (the mitsuba extra: "
                    "pip install mitsuba), not pbrt.")
    m.add_argument("scene", type=Path, metavar="SCENE.xml", help="a Mitsuba 3 XML scene")
    m.add_argument("-o", "--output", type=Path, default=None, metavar="FILE",
                   help="image to write (default: the scene's name with .exr, beside the scene, as "
                        "Mitsuba writes it)")
    m.add_argument("-m", "--mode", default=DEFAULT_VARIANT, metavar="VARIANT",
                   help=f"a spectral Mitsuba variant (default {DEFAULT_VARIANT}, where the plugin "
                        "runs compiled at no cost per sample; scalar_spectral calls it in Python "
                        "once per sample, 5-7x slower; an RGB or mono variant is refused)")
    m.add_argument("-D", "--define", type=_define, action="append", default=[], metavar="KEY=VALUE",
                   help="define $KEY in the scene, as Mitsuba's -D (repeatable)")
    m.add_argument("-s", "--sensor", type=int, default=0, metavar="INDEX",
                   help="index of the sensor to render with, in declaration order (default 0)")
    m.add_argument("-a", "--append", action="append", default=[], metavar="PATH1;PATH2",
                   help="add entries to the resource search path, as Mitsuba's -a (repeatable)")
    m.add_argument("-t", "--threads", type=positive_int, default=None, metavar="N",
                   help="render threads (default: all cores)")
    m.add_argument("--spp", type=positive_int, default=None, metavar="N",
                   help="samples per pixel (default: the scene's sampler's)")
    m.add_argument("--seed", type=int, default=0, metavar="N", help="the sampler's seed (default 0)")
    m.set_defaults(func=cmd_mitsuba)
