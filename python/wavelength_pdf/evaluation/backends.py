"""The renderers the evaluation can run (design §6.4), by name: what each needs and how it runs
one evaluation. The command layer (:mod:`wavelength_pdf.cli.evaluate`) asks this registry
instead of testing renderer names.

- ``pbrt``: this repository's renderer (:func:`.protocol.evaluate`); it also answers the
  scene queries (emission, materials), so whole-scene tables and ``--reflectances`` work.
- ``mitsuba``: Mitsuba 3 with the ``wavelength_table`` plugin (:mod:`.render_mitsuba`);
  needs no ``pbrt``, reads the ``.xml`` twin of a scene.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from wavelength_pdf.evaluation.protocol import Config, Evaluation


@dataclass(frozen=True)
class Backend:
    name: str
    #: Runs this repository's ``pbrt`` (found by :func:`wavelength_pdf.renderer.find_pbrt`).
    uses_pbrt: bool
    #: Answers the scene queries: whole-scene tables and ``--reflectances``.
    scene_queries: bool
    #: The suffix of the scene files it reads (the demo scene's twin).
    scene_suffix: str
    #: ``(scene, spectrum, outdir, config, table=, progress=, optimizer_progress=,
    #: keep_emitters=, reflectances=) -> Evaluation``.
    evaluate: Callable[..., Evaluation]


def _pbrt_evaluate(scene: Path, spectrum, outdir: Path, config: Config, **kw) -> Evaluation:
    from wavelength_pdf.evaluation.protocol import evaluate
    return evaluate(scene, spectrum, outdir, config, **kw)


def _mitsuba_evaluate(scene: Path, spectrum, outdir: Path, config: Config, *, keep_emitters: bool = False,
                      reflectances=None, **kw) -> Evaluation:
    # scene_queries is False: the command layer refuses both before anything runs.
    assert not keep_emitters and reflectances is None
    try:
        from wavelength_pdf.evaluation import render_mitsuba
    except ImportError as e:
        raise ValueError(f"--renderer mitsuba needs Mitsuba 3 (the mitsuba extra): pip install "
                         f"mitsuba ({e})") from None
    return render_mitsuba.evaluate(scene, spectrum, outdir, config, **kw)


BACKENDS: dict[str, Backend] = {
    "pbrt": Backend("pbrt", uses_pbrt=True, scene_queries=True, scene_suffix=".pbrt",
                    evaluate=_pbrt_evaluate),
    "mitsuba": Backend("mitsuba", uses_pbrt=False, scene_queries=False, scene_suffix=".xml",
                       evaluate=_mitsuba_evaluate),
}


def backend(name: str) -> Backend:
    try:
        return BACKENDS[name]
    except KeyError:
        raise ValueError(f"unknown renderer {name!r}; choose one of: {', '.join(BACKENDS)}") from None
