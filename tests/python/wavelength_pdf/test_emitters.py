"""Which parameter carries a light's spectrum (design §5.4): the rule of
``wavelength_pdf.emitters``, pinned by tests/data/emitter-parameters.csv, which the
renderer's test (pbrt-v4 ``EmissionParameterName``) reads too."""
from __future__ import annotations

import csv
import warnings

import numpy as np
import pytest

from wavelength_pdf.emitters import INTENSITY_LIGHTS, emission_parameter
from wavelength_pdf.scene_spectra import NotOptimizableWarning, scene_spectra

from repo_paths import REPO

ROWS = [(r["directive"], r["type"], r["parameter"]) for r in csv.DictReader(
    line for line in open(REPO / "tests" / "data" / "emitter-parameters.csv", encoding="utf-8")
    if not line.startswith("#"))]


@pytest.mark.parametrize("directive, type_, parameter", ROWS)
def test_emission_parameter_as_the_shared_table_says(directive, type_, parameter):
    assert emission_parameter(directive, type_) == parameter


def test_the_table_names_every_intensity_light():
    assert {t for d, t, p in ROWS if p == "I"} == INTENSITY_LIGHTS
    # An area light is never an intensity light, whatever its type is called.
    assert emission_parameter("AreaLightSource", "point") == "L"


@pytest.mark.parametrize("directive, type_, parameter", ROWS)
def test_the_scene_reader_reads_that_parameter(tmp_path, directive, type_, parameter):
    """A lamp spectrum under the named parameter is the light's; under the other name it is
    not (the light then emits its colour space's illuminant, which is not this line)."""
    shape = '\nShape "sphere"' if directive == "AreaLightSource" else ""
    other = "L" if parameter == "I" else "I"
    got = {}
    for name in (parameter, other):
        scene = tmp_path / f"{name}.pbrt"
        scene.write_text(f'WorldBegin\n{directive} "{type_}" "spectrum {name}" '
                         f'[ 500 0 550 1 600 0 ]{shape}\n')
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotOptimizableWarning)
            spectra = scene_spectra(scene)
        assert len(spectra) == 1
        got[name] = spectra[0]
    lam = np.array([400.0, 550.0, 700.0])
    assert np.interp(lam, got[parameter].wavelengths, got[parameter].values,
                     left=0, right=0).tolist() == [0.0, 1.0, 0.0]
    assert np.interp(400.0, got[other].wavelengths, got[other].values) > 0  # the illuminant
