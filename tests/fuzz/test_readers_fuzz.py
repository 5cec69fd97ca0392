"""Fuzz tests of the Python readers (Hypothesis): the wavelength-table reader, the spectrum
readers (.spd and LSPDD .csv through load_spectrum) and the scene-spectra reader.

Each input either reads, and then the result keeps the reader's promises (design §2 for
tables, §3 for spectra), or raises the reader's documented error (TableError,
SpectrumError) whose message starts ``FILE:LINE: reason``: never another exception, and
never an accepted result that breaks a promise.

The inputs are built from the formats' own pieces (headers, numbers at the extremes of
float64, separators, comments, directives) mixed with arbitrary text, so that most of them
get past the first line. The default profile is derandomized and small (part of the test
suite: 40 examples per reader); ``HYPOTHESIS_PROFILE=fuzz`` runs 20000. The table texts also
go to the header (through ``pbrt --wavelength-pdf``), which must agree with the Python reader.
"""
from __future__ import annotations

import os
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from wavelength_pdf.scene_spectra import scene_spectra  # noqa: E402
from wavelength_pdf.spectra import SpectrumError, load_spectrum  # noqa: E402
from wavelength_pdf.table import TableError, read_table  # noqa: E402

settings.register_profile("ci", max_examples=40, derandomize=True, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("fuzz", max_examples=20000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# --- Pieces of the formats ---------------------------------------------------------------

#: Numbers a reader must survive: ordinary, extreme, signed zeros, non-finite, malformed.
NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(min_value=300, max_value=900).map(lambda x: f"{x:.3f}"),
    st.floats(min_value=0, max_value=1).map(lambda x: f"{x:.6g}"),
    st.integers(min_value=-10**30, max_value=10**30).map(str),
    st.sampled_from(["0", "-0", "1e300", "1e-300", "1e308", "1e309", "-1e309", "4.9e-324",
                     "nan", "NaN", "inf", "-inf", "+1", ".5", "5.", "1e", "0x10", "1_000",
                     "", " ", "--1", "1,5", "١٢"]),
)
TEXT = st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=20)


def lines_of(line: st.SearchStrategy[str], max_lines: int = 12) -> st.SearchStrategy[str]:
    sep = st.sampled_from(["\n", "\r\n", "\n\n", "\r"])
    return st.lists(st.tuples(line, sep), max_size=max_lines).map(
        lambda rows: "".join(a + b for a, b in rows))


def csv_row(n: int) -> st.SearchStrategy[str]:
    return st.lists(NUMBERS, min_size=max(0, n - 1), max_size=n + 1).map(",".join)


def mutated(valid: st.SearchStrategy[list[str]], noise: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
    """Valid lines with up to two of them replaced (or new ones inserted) by noise, joined."""
    edits = st.lists(st.tuples(st.integers(0, 40), st.booleans(), noise), max_size=2)

    def apply(args):
        lines, changes = args
        lines = list(lines)
        for at, insert, text in changes:
            i = at % (len(lines) + 1)
            if insert or i == len(lines):
                lines.insert(i, text)
            else:
                lines[i] = text
        return "\n".join(lines) + "\n"

    return st.tuples(valid, edits).map(apply)


WAVELENGTHS = st.lists(st.floats(min_value=360, max_value=830, allow_nan=False), min_size=2,
                       max_size=12, unique=True).map(sorted)
POSITIVE = st.floats(min_value=0, max_value=1e6, allow_nan=False).map(lambda x: f"{x:.6g}")


@st.composite
def valid_table_lines(draw):
    grid = draw(WAVELENGTHS)
    rows = [",".join([f"{lam:.6f}"] + [draw(POSITIVE) for _ in range(4)]) for lam in grid]
    # every density needs some mass
    rows = [r if i else ",".join([r.split(",")[0]] + ["1"] * 4) for i, r in enumerate(rows)]
    return ["# fuzz", "lambda_nm,pdf0,pdf1,pdf2,pdf3", *rows]


@st.composite
def valid_spd_lines(draw):
    grid = draw(st.lists(st.floats(min_value=380, max_value=780, allow_nan=False), min_size=2,
                         max_size=12, unique=True).map(sorted))
    return [f"{lam:.6f} {draw(POSITIVE) if i else '1'}" for i, lam in enumerate(grid)]


@st.composite
def valid_lspdd_lines(draw):
    return ["# Model : fuzz", "wavelength, intensity",
            *[line.replace(" ", ",") for line in draw(valid_spd_lines())]]


@st.composite
def valid_scene_lines(draw):
    pairs = " ".join(line for line in draw(valid_spd_lines()))
    light = draw(st.sampled_from([
        f'LightSource "point" "spectrum I" [ {pairs} ]',
        f'LightSource "infinite" "spectrum L" [ {pairs} ] "float scale" [ 2 ]',
        'LightSource "spot" "blackbody I" [ 3000 ]',
        f'AttributeBegin\nAreaLightSource "diffuse" "spectrum L" [ {pairs} ]\nShape "sphere"\nAttributeEnd',
        'LightSource "distant" "spectrum L" "stdillum-D65"',
    ]))
    return ["Camera \"perspective\"", "WorldBegin", *light.split("\n")]


TABLE_TEXT = st.one_of(
    mutated(valid_table_lines(), st.one_of(csv_row(5), NUMBERS, TEXT)),
    # commented CSV layout
    st.tuples(lines_of(st.one_of(st.just("# comment"), TEXT.map(lambda t: "#" + t)), 3),
              st.sampled_from(["lambda_nm,pdf0,pdf1,pdf2,pdf3", "lambda_nm,pdf0,pdf1,pdf2",
                               "LAMBDA_NM,PDF0,PDF1,PDF2,PDF3", "", "x"]),
              lines_of(st.one_of(csv_row(5), csv_row(5).map(lambda r: r + ","), TEXT), 10))
    .map(lambda t: t[0] + t[1] + "\n" + t[2]),
    # headerless 4 x 81 layout
    lines_of(st.one_of(csv_row(81), st.lists(NUMBERS, min_size=81, max_size=81).map(",".join)), 5),
    TEXT,
)

SPD_TEXT = st.one_of(
    mutated(valid_spd_lines(), st.one_of(st.tuples(NUMBERS, NUMBERS).map(" ".join), NUMBERS, TEXT)),
    lines_of(st.one_of(st.tuples(NUMBERS, NUMBERS).map(" ".join), NUMBERS,
                       TEXT.map(lambda t: "# " + t), TEXT)),
    TEXT,
)

LSPDD_TEXT = st.one_of(mutated(valid_lspdd_lines(), st.one_of(
    st.tuples(NUMBERS, NUMBERS).map(",".join), csv_row(3), TEXT)), st.tuples(
    lines_of(st.one_of(st.just("# Category : Fluorescent"), TEXT.map(lambda t: "# Model : " + t),
                       TEXT.map(lambda t: "#" + t)), 4),
    st.sampled_from(["wavelength, intensity", "wavelength,intensity", "", "lambda, value"]),
    lines_of(st.one_of(st.tuples(NUMBERS, NUMBERS).map(",".join), csv_row(3), TEXT), 10),
).map(lambda t: t[0] + t[1] + "\n" + t[2]))

DIRECTIVES = st.sampled_from([
    "WorldBegin", "AttributeBegin", "AttributeEnd", "Shape \"sphere\"",
    "AreaLightSource \"diffuse\"", "LightSource \"infinite\"", "LightSource \"point\"",
    "LightSource \"spot\"", "LightSource \"distant\"", "LightSource \"goniometric\"",
    "\"spectrum L\"", "\"spectrum I\"", "\"blackbody L\"", "\"rgb L\"", "\"float scale\"",
    "\"float power\"", "\"spectrum L\" \"stdillum-D65\"", "\"spectrum L\" \"nope\"",
    "\"spectrum L\" \"d.spd\"", "\"spectrum L\" \"missing.spd\"", "Include \"d.spd\"",
    "Include \"self.pbrt\"", "Import \"x.pbrt\"", "[", "]", "\"", "\\", "#",
    "ObjectBegin \"o\"", "ObjectEnd", "Material \"diffuse\"",
])
SCENE_NOISE = st.lists(st.one_of(DIRECTIVES, NUMBERS, st.lists(NUMBERS, max_size=6).map(
    lambda v: "[ " + " ".join(v) + " ]"), TEXT), max_size=8).map(" ".join)
SCENE_TEXT = st.one_of(mutated(valid_scene_lines(), SCENE_NOISE), lines_of(SCENE_NOISE, 14))

# --- Checks ---------------------------------------------------------------------------------


def check_message(err: Exception, path: Path) -> None:
    """The message starts with the file and line: ``PATH:LINE: reason`` (the file at fault: an
    included or referenced one may be named instead), or ``PATH: reason`` when the fault is
    the file as a whole (empty, no emitters), never a bare reason."""
    msg = str(err)
    m = re.match(r"^(?P<file>[^:]+)(?P<line>:\d+)?(:\d+)?: \S", msg)
    assert m, f"no FILE:LINE: reason in {msg!r}"
    named = Path(m["file"])
    assert named == path or named.parent == path.parent, f"{msg!r} does not name {path}"
    if m["line"] is None:
        text = path.read_text(encoding="utf-8", errors="replace") if path.exists() else ""
        assert named == path, msg
        assert WHOLE_FILE.search(msg), f"no line in {msg!r} for {text[:200]!r}"


#: Reasons that concern a whole file, so that a message without a line is right.
WHOLE_FILE = re.compile(r"no emitters|no data|no numbers|empty|no rows|no such file|"
                        r"is a directory|cannot read|no energy|energy|header|distinct emitter")


def write(text: str, suffix: str, directory: Path) -> Path:
    fd, name = tempfile.mkstemp(suffix=suffix, dir=directory)
    with os.fdopen(fd, "w", encoding="utf-8", errors="surrogatepass", newline="") as f:
        f.write(text)
    return Path(name)


@pytest.fixture(scope="module")
def workdir():
    with tempfile.TemporaryDirectory(prefix="wavelength-pdf-fuzz-") as d:
        Path(d, "d.spd").mkdir()  # a directory where a file is expected
        Path(d, "self.pbrt").write_text('Include "self.pbrt"\n')
        yield Path(d)


# --- The readers -------------------------------------------------------------------------------


@given(TABLE_TEXT)
def test_read_table_reads_or_raises_table_error(workdir, text):
    path = write(text, ".csv", workdir)
    try:
        t = read_table(path)
    except TableError as e:
        check_message(e, path)
        return
    finally:
        path.unlink()
    # An accepted table keeps design §2's promises.
    assert t.grid.ndim == 1 and t.grid.size >= 2 and np.all(np.isfinite(t.grid))
    assert np.all(np.diff(t.grid) > 0)
    assert t.pdfs.shape == (4, t.grid.size)
    assert np.all(np.isfinite(t.pdfs)) and np.all(t.pdfs >= 0)
    mass = np.sum(0.5 * (t.pdfs[:, 1:] + t.pdfs[:, :-1]) * np.diff(t.grid), axis=1)
    np.testing.assert_allclose(mass, 1.0, rtol=1e-9)


@pytest.mark.parametrize("suffix, strategy", [(".spd", SPD_TEXT), (".csv", LSPDD_TEXT)])
def test_load_spectrum_reads_or_raises_spectrum_error(workdir, suffix, strategy):
    @given(strategy)
    def run(text):
        path = write(text, suffix, workdir)
        try:
            s = load_spectrum(str(path))
        except SpectrumError as e:
            check_message(e, path)
            return
        finally:
            path.unlink()
        check_spectrum(s)

    run()


def check_spectrum(s) -> None:
    """Design §3: finite, strictly increasing wavelengths; finite, non-negative values."""
    assert s.wavelengths.ndim == 1 and s.wavelengths.size >= 2
    assert s.values.shape == s.wavelengths.shape
    assert np.all(np.isfinite(s.wavelengths)) and np.all(np.diff(s.wavelengths) > 0)
    assert np.all(np.isfinite(s.values)) and np.all(s.values >= 0)
    assert np.any(s.values > 0)


@given(SCENE_TEXT)
def test_scene_spectra_reads_or_raises_spectrum_error(workdir, text):
    path = write(text, ".pbrt", workdir)
    try:
        spectra = scene_spectra(path)
    except SpectrumError as e:
        check_message(e, path)
        return
    finally:
        path.unlink()
    for s in spectra:
        check_spectrum(s)


#: A scene for pbrt to parse without rendering (--emission-spectrum): it reads the table first.
_ONE_LAMP = 'WorldBegin\nLightSource "point" "spectrum I" [ 400 1 700 1 ]\n'


@given(TABLE_TEXT)
def test_python_reader_and_header_agree_on_mangled_tables(pbrt, workdir, text):
    """Design §2.1a, §2.3: the Python reader and the header (as pbrt --wavelength-pdf reads a
    table) accept the same texts, and refuse the others at the same line for the same reason
    (a quoted token may be written differently: Python's repr, the header's \\xNN)."""
    path = write(text, ".csv", workdir)
    scene = workdir / "one-lamp.pbrt"
    scene.write_text(_ONE_LAMP)
    try:
        try:
            read_table(path)
            python = "accepted"
        except TableError as e:
            python = str(e)
        run = subprocess.run([str(pbrt), "--quiet", "--wavelength-pdf", str(path),
                              "--emission-spectrum", str(workdir / "e.spd"), str(scene)],
                             capture_output=True, text=True, errors="replace", timeout=60)
    finally:
        path.unlink()
    header = "accepted" if run.returncode == 0 else run.stderr.strip().removeprefix("pbrt: ")
    assert run.returncode in (0, 1), run.stderr
    cut = " cannot parse number "
    assert python.split(cut)[0] == header.split(cut)[0], (text, python, header)


def test_the_strategies_reach_past_the_first_line(workdir):
    """The fuzz inputs are not all rejected at once: some tables, spectra and scenes read."""
    ok = {"table": 0, "spd": 0, "scene": 0}

    @settings(max_examples=30, derandomize=True, deadline=None)
    @given(TABLE_TEXT, SPD_TEXT, SCENE_TEXT)
    def run(table, spd, scene):
        for kind, text, suffix, read, error in (
            ("table", table, ".csv", read_table, TableError),
            ("spd", spd, ".spd", lambda p: load_spectrum(str(p)), SpectrumError),
            ("scene", scene, ".pbrt", scene_spectra, SpectrumError),
        ):
            path = write(text, suffix, workdir)
            try:
                read(path)
                ok[kind] += 1
            except error:
                pass
            finally:
                path.unlink()

    run()
    # A reader that rejected everything would make the tests above vacuous.
    assert ok["table"] >= 1 and ok["spd"] >= 1 and ok["scene"] >= 1, ok
