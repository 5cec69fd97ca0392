"""The evaluation's renderer registry (wavelength_pdf.evaluation.backends, design §6.4): the
command layer's choices are the registry's, every renderer has the demo scene in its own
format, and what a renderer cannot do is refused before anything runs."""
from __future__ import annotations

import pytest

from wavelength_pdf.cli import evaluate as commands
from wavelength_pdf.cli import main
from wavelength_pdf.evaluation.backends import BACKENDS, backend
from wavelength_pdf.evaluation.protocol import WHOLE_SCENE, Config


def test_every_backend_has_the_demo_scene_in_its_format():
    for b in BACKENDS.values():
        assert commands.DEMO_SCENE.with_suffix(b.scene_suffix).is_file(), b.name


def test_the_commands_offer_exactly_the_registry(capsys):
    with pytest.raises(SystemExit):
        main(["evaluate", "--help"])
    out = capsys.readouterr().out
    assert "{" + ",".join(BACKENDS) + "}" in out


def test_an_unknown_renderer_names_the_known_ones():
    with pytest.raises(ValueError, match="unknown renderer 'cycles'; choose one of: pbrt, mitsuba"):
        backend("cycles")


@pytest.mark.parametrize("name", [n for n, b in BACKENDS.items() if not b.scene_queries])
def test_scene_queries_are_refused_where_the_renderer_cannot_answer_them(name, tmp_path):
    # Refused before the spectrum is even read: the scene and spectrum here do not exist.
    with pytest.raises(ValueError, match="need the pbrt renderer"):
        commands.run_one(tmp_path / "missing.xml", WHOLE_SCENE, tmp_path, Config(), None, renderer=name)
