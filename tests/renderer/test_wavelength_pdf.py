"""``pbrt --wavelength-pdf TABLE`` on the project's Cornell box (design §1, §5.2), with the real binary.

(a) Unbiased: with the scene's tri-band lamp, the image rendered with a table converges to the
    image rendered with pbrt-v4's visible sampling, for the optimizer's table, for every table of
    ../shared/tables/reference-4x81/ (made for other lamps) and for a lopsided table.
(b) Every class of bad table of design §2 stops pbrt before rendering: exit status 1 and
    ``pbrt: FILE:LINE: reason`` (``FILE: reason`` for a missing file), no image written.
(c) A table whose mixture density is zero where the lamp emits gets the warning of design §1 (and
    biases the image); ``--wavelength-pdf-defensive 0.01`` removes both.

Statistics. Each sampler renders twice with different seeds. The per-pixel difference of the
two renders estimates the per-pixel variance (E[(a - b)^2] = 2 var), hence the standard error
of the image mean, per RGB channel. A table passes when |mean_table - mean_visible| < 4 sigma,
sigma = sqrt(se_table^2 + se_visible^2), and each comparison asserts 4 sigma < 2% of the mean,
so a 2% bias cannot hide in the noise. To keep the noise (and the run time) low the scene is
rendered from a copy that uses the "sobol" sampler (randomized quasi-Monte Carlo: two seeds
are two independent scrambles), at 16 x 16 pixels with direct lighting only (--maxdepth 1),
and the top quarter of the image, where the lamp itself is seen (bright, noisy edges), is left
out of the means. Every wavelength-dependent factor (the lamp's lines, the RGB reflectances)
still enters each path.
"""
from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from wavelength_pdf.exr import read_rgb

REPO = Path(__file__).resolve().parents[2]
from repo_paths import SHARED  # noqa: E402  (read-only; may be absent)
from input_files import EDGE_TABLES, edge_table_cases, make_fifo  # noqa: E402
SCENE = REPO / "scenes" / "cornell-box" / "scene.pbrt"
OPTIMIZED = REPO / "tests" / "data" / "tables" / "tri-band-fluorescent-optimized.csv"
REFERENCE_DIR = SHARED / "tables" / "reference-4x81"
REFERENCE_TABLES = sorted(p.name for p in REFERENCE_DIR.glob("*.csv")) if REFERENCE_DIR.is_dir() else []

RESOLUTION = "16x16"
MAX_DEPTH = "1"
VISIBLE_SPP = 4096     # the reference, once per session
TABLE_SPP = (1024, 4096)  # a table's render; the second only if the first is too noisy
DETECT = 0.02          # the smallest relative bias every comparison must be able to see
GRID = np.arange(380.0, 781.0, 5.0)
# The scene's lamp (spectra/tri-band-fluorescent.spd): its red europium line at 611 nm.
RED_BAND = (590.0, 640.0)


# ---------------------------------------------------------------------------------------------
# Rendering and statistics
# ---------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Path:
    """The Cornell box with the sobol sampler, the lamp's spectrum path made absolute."""
    text = SCENE.read_text()
    text, n_sampler = re.subn(r'Sampler\s+"independent"', 'Sampler "sobol"', text)
    spd = '"tri-band-fluorescent.spd"'  # beside the scene (a copy of spectra/'s)
    assert n_sampler == 1 and spd in text, "scenes/cornell-box/scene.pbrt changed: update this test"
    text = text.replace(spd, f'"{REPO / "spectra" / "tri-band-fluorescent.spd"}"')
    out = tmp_path_factory.mktemp("cornell") / "scene.pbrt"
    out.write_text(text)
    return out


@dataclass
class Run:
    returncode: int
    stderr: str
    image: np.ndarray | None


def run_pbrt(pbrt: Path, scene: Path, out: Path, *args: str, spp: int = 1, seed: int = 0) -> Run:
    """One render; the image is read when pbrt succeeded."""
    out.unlink(missing_ok=True)
    cmd = [str(pbrt), "--quiet", "--spp", str(spp), "--seed", str(seed), "--resolution", RESOLUTION,
           "--maxdepth", MAX_DEPTH, "--outfile", str(out), *args, str(scene)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    image = read_rgb(out) if proc.returncode == 0 else None
    return Run(proc.returncode, proc.stderr, image)


@dataclass
class Estimate:
    """Per-channel image mean (RGB) over the compared rows and its standard error."""

    mean: np.ndarray
    se: np.ndarray
    stderr: str


def estimate(pbrt: Path, scene: Path, tmp: Path, args: tuple[str, ...], spp: int) -> Estimate:
    """Render twice (seeds 1 and 2) and estimate the image mean and its standard error."""
    runs = [run_pbrt(pbrt, scene, tmp / f"seed{s}.exr", *args, spp=spp, seed=s) for s in (1, 2)]
    for r in runs:
        assert r.returncode == 0, r.stderr
    h = runs[0].image.shape[0]
    a, b = (r.image[h // 4:] for r in runs)  # the lamp itself is in the top quarter
    n = a.shape[0] * a.shape[1]
    mean = 0.5 * (a.mean(axis=(0, 1)) + b.mean(axis=(0, 1)))
    # var(pixel) = E[(a - b)^2] / 2; the mean of 2 n pixels has variance var / (2 n).
    se = np.sqrt(((a - b) ** 2).mean(axis=(0, 1)) / 2 / (2 * n))
    return Estimate(mean, se, runs[0].stderr)


@pytest.fixture(scope="module")
def visible(pbrt, scene, tmp_path_factory) -> Estimate:
    """The reference: pbrt-v4's visible sampling (360..830 nm)."""
    tmp = tmp_path_factory.mktemp("visible")
    return estimate(pbrt, scene, tmp, ("--wavelength-sampling", "visible"), VISIBLE_SPP)


def compare_with_visible(pbrt, scene, tmp: Path, visible: Estimate, args: tuple[str, ...],
                         what: str) -> Estimate:
    """Assert that a sampler's image converges to the visible-sampling image.

    (The table covers 380..780 nm, the visible sampler 360..830 nm: the lamp's light outside
    380..780 nm is below 2e-4 of every channel, far below the noise.)
    """
    for spp in TABLE_SPP:
        est = estimate(pbrt, scene, tmp, args, spp)
        sigma = np.sqrt(est.se ** 2 + visible.se ** 2)
        if np.all(4 * sigma < DETECT * visible.mean):
            break
    diff = est.mean - visible.mean
    assert np.all(4 * sigma < DETECT * visible.mean), (
        f"{what}: too noisy to detect a {DETECT:.0%} bias: sigma/mean = {sigma / visible.mean}")
    assert np.all(np.abs(diff) < 4 * sigma), (
        f"{what}: image mean {est.mean} vs visible {visible.mean}: difference {diff} "
        f"({diff / sigma} sigma)")
    return est


# ---------------------------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------------------------

def write_table(path: Path, pdfs: np.ndarray, grid: np.ndarray = GRID) -> Path:
    """A CSV table (design §2) with the given node values (4 x len(grid))."""
    lines = ["# test table", "lambda_nm,pdf0,pdf1,pdf2,pdf3"]
    lines += [f"{l:g}," + ",".join(f"{v:.9g}" for v in pdfs[:, i]) for i, l in enumerate(grid)]
    path.write_text("\n".join(lines) + "\n")
    return path


def lopsided_pdfs() -> np.ndarray:
    """All four densities crowded to the blue end (decay lengths 40..85 nm over a 400 nm grid),
    on a floor 50 times below their peaks: non-zero everywhere."""
    return np.array([0.02 + np.exp(-(GRID - 380.0) / (40.0 + 15.0 * k)) for k in range(4)])


def read_pdfs(path: Path) -> np.ndarray:
    """Node values (4 x 81) of a table on the default grid."""
    from wavelength_pdf.table import read_table
    t = read_table(path)
    assert np.allclose(t.grid, GRID)
    return np.asarray(t.pdfs)


def zero_mixture_intervals(pdfs: np.ndarray, grid: np.ndarray = GRID) -> list[tuple[float, float]]:
    """Stretches between neighbouring nodes where all four densities vanish (merged)."""
    zero = np.all(pdfs == 0, axis=0)
    out: list[tuple[float, float]] = []
    for i in range(len(grid) - 1):
        if zero[i] and zero[i + 1]:
            if out and out[-1][1] == grid[i]:
                out[-1] = (out[-1][0], grid[i + 1])
            else:
                out.append((grid[i], grid[i + 1]))
    return out


def warnings_of(stderr: str) -> list[str]:
    return [l for l in stderr.splitlines() if l.startswith("pbrt: warning:")]


def gap_warnings(stderr: str) -> list[str]:
    return [w for w in warnings_of(stderr) if "sampling density is zero" in w]


# ---------------------------------------------------------------------------------------------
# (a) Unbiased
# ---------------------------------------------------------------------------------------------

def test_optimized_table_converges_to_visible_sampling(pbrt, scene, tmp_path, visible):
    assert not zero_mixture_intervals(read_pdfs(OPTIMIZED))
    est = compare_with_visible(pbrt, scene, tmp_path, visible, ("--wavelength-pdf", str(OPTIMIZED)),
                               "optimized table")
    assert not warnings_of(est.stderr), est.stderr


@pytest.mark.parametrize("name", REFERENCE_TABLES or [pytest.param(
    None, marks=pytest.mark.skip(reason="../shared/tables/reference-4x81 is not present"))])
def test_reference_table_converges_to_visible_sampling(pbrt, scene, tmp_path, visible, name):
    """Reference tables were made for other lamps. Where one has no zero mixture density, it
    renders this lamp unbiased and without a warning; where it has, the warning fires, the
    image is biased, and the defensive mixture makes it unbiased again."""
    table = REFERENCE_DIR / name
    gaps = zero_mixture_intervals(read_pdfs(table))
    args = ("--wavelength-pdf", str(table))
    if not gaps:
        est = compare_with_visible(pbrt, scene, tmp_path, visible, args, name)
        assert not warnings_of(est.stderr), est.stderr
        return
    # The lamp has a continuum over all of 360..830 nm, so it emits in every gap.
    run = run_pbrt(pbrt, scene, tmp_path / "x.exr", *args)
    assert run.returncode == 0 and gap_warnings(run.stderr), run.stderr
    est = compare_with_visible(pbrt, scene, tmp_path, visible,
                               args + ("--wavelength-pdf-defensive", "0.1"), f"{name} + defensive 0.1")
    assert not gap_warnings(est.stderr), est.stderr


def test_lopsided_table_converges_to_visible_sampling(pbrt, scene, tmp_path, visible):
    table = write_table(tmp_path / "lopsided.csv", lopsided_pdfs())
    pdfs = read_pdfs(table)
    cdf = np.cumsum(pdfs.mean(axis=0))
    median = GRID[np.searchsorted(cdf, cdf[-1] / 2)]
    assert median <= 450, f"not lopsided: the mixture's median is at {median} nm"
    assert np.all(pdfs > 0)
    compare_with_visible(pbrt, scene, tmp_path, visible, ("--wavelength-pdf", str(table)), "lopsided table")


# ---------------------------------------------------------------------------------------------
# (c) Zero mixture density where the lamp emits: warning, bias, and the defensive fix
# ---------------------------------------------------------------------------------------------

def test_gap_over_an_emission_line_warns_biases_and_the_defensive_share_fixes_it(
        pbrt, scene, tmp_path, visible):
    # The optimized table with all four densities zero over the lamp's red line.
    pdfs = read_pdfs(OPTIMIZED).copy()
    pdfs[:, (GRID >= RED_BAND[0]) & (GRID <= RED_BAND[1])] = 0
    table = write_table(tmp_path / "gap.csv", pdfs)
    assert zero_mixture_intervals(pdfs) == [RED_BAND]

    est = estimate(pbrt, scene, tmp_path, ("--wavelength-pdf", str(table)), TABLE_SPP[0])
    warnings = gap_warnings(est.stderr)
    assert len(warnings) == 1, est.stderr
    light_line = next(i for i, l in enumerate(scene.read_text().splitlines(), 1) if "AreaLightSource" in l)
    w = warnings[0]
    assert f"{scene}:{light_line}:" in w, w                      # the emitter's file:line
    assert f"[{RED_BAND[0]:g}, {RED_BAND[1]:g}] nm" in w, w      # the interval
    assert "--wavelength-pdf-defensive 0.01" in w, w             # the fix
    # The red line is never sampled: the red channel falls far below the reference.
    sigma = np.sqrt(est.se ** 2 + visible.se ** 2)
    assert est.mean[0] < visible.mean[0] - 10 * sigma[0], (est.mean, visible.mean, sigma)
    assert est.mean[0] < 0.9 * visible.mean[0], (est.mean, visible.mean)

    # The documented fix: no warning, and the image converges to the reference again. (Any
    # positive share is unbiased, but 0.01 gives the red line so few samples that its noise
    # would hide a 2% bias at this spp; the comparison runs with a share of 0.5.)
    run = run_pbrt(pbrt, scene, tmp_path / "fixed.exr", "--wavelength-pdf", str(table),
                   "--wavelength-pdf-defensive", "0.01")
    assert run.returncode == 0, run.stderr
    assert not warnings_of(run.stderr), run.stderr
    compare_with_visible(pbrt, scene, tmp_path, visible,
                         ("--wavelength-pdf", str(table), "--wavelength-pdf-defensive", "0.5"),
                         "gap table + defensive 0.5")


def test_a_narrow_table_warns_about_emission_outside_its_range(pbrt, scene, tmp_path):
    # A table on 450..650 nm: the lamp's 404.7 and 435.8 nm lines are outside it.
    grid = np.arange(450.0, 651.0, 5.0)
    table = write_table(tmp_path / "narrow.csv", np.ones((4, len(grid))), grid)
    run = run_pbrt(pbrt, scene, tmp_path / "x.exr", "--wavelength-pdf", str(table))
    assert run.returncode == 0, run.stderr
    w = [l for l in warnings_of(run.stderr) if "outside the range" in l]
    assert len(w) == 1, run.stderr
    assert "[360, 450] and [650, 830] nm" in w[0] and "of its luminance" in w[0], w[0]


# ---------------------------------------------------------------------------------------------
# (b) Bad tables
# ---------------------------------------------------------------------------------------------

#: One file per reject class of design §2.3 from the shared edge cases (their line and reason
#: in tests/data/tables/edge/expected.csv, which every table reader's test reads).
BAD_TABLES = ["nan.csv", "inf.csv", "negative.csv", "zero.csv", "repeated.csv", "six-columns.csv",
              "one-node.csv", "wide-ragged-short.csv"]


@pytest.mark.parametrize("kind", BAD_TABLES)
def test_bad_table_stops_pbrt_before_rendering(pbrt, scene, tmp_path, kind):
    line, reason = next((line, reason) for name, nodes, line, reason in edge_table_cases()
                        if name == kind)
    table = EDGE_TABLES / kind
    out = tmp_path / "never.exr"
    run = run_pbrt(pbrt, scene, out, "--wavelength-pdf", str(table), spp=64)
    assert run.returncode == 1, run.stderr
    assert f"pbrt: {table}:{line}: " in run.stderr and reason in run.stderr, run.stderr
    assert not out.exists(), "an image was written"


@pytest.mark.parametrize("name, nodes, line, reason", edge_table_cases(),
                         ids=[c[0] for c in edge_table_cases()])
def test_edge_tables_as_pbrt_reads_them(pbrt, scene, tmp_path, name, nodes, line, reason):
    """The shared edge cases (tests/data/tables/edge, read alike by the Python reader and the
    header): pbrt refuses what they refuse, at the same line, and reads what they read."""
    table = EDGE_TABLES / name
    # --emission-spectrum parses the scene and renders nothing: the table is read first.
    proc = subprocess.run([str(pbrt), "--quiet", "--wavelength-pdf", str(table),
                           "--emission-spectrum", str(tmp_path / "e.spd"), str(scene)],
                          capture_output=True, text=True, timeout=120)
    if nodes is not None:
        assert proc.returncode == 0, proc.stderr
        return
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr.startswith(f"pbrt: {table}:{line}: ") and reason in proc.stderr, proc.stderr


def test_fifo_or_device_as_table_stops_pbrt_at_once(pbrt, scene, tmp_path):
    """A FIFO held pbrt for ever, /dev/zero was read without end (design §2.3: regular files
    of at most 64 MiB)."""
    for table in (make_fifo(tmp_path, "fifo.csv"), Path("/dev/zero")):
        out = tmp_path / "never.exr"
        try:
            run = run_pbrt(pbrt, scene, out, "--wavelength-pdf", str(table))
        except subprocess.TimeoutExpired:
            pytest.fail(f"pbrt still reading {table} after 120 s")
        assert run.returncode == 1, run.stderr
        assert f"pbrt: {table}: not a regular file" in run.stderr, run.stderr
        assert not out.exists()


def test_missing_table_stops_pbrt(pbrt, scene, tmp_path):
    out = tmp_path / "never.exr"
    missing = tmp_path / "no-such-table.csv"
    run = run_pbrt(pbrt, scene, out, "--wavelength-pdf", str(missing))
    assert run.returncode == 1 and f"pbrt: {missing}: no such file" in run.stderr, run.stderr
    assert not out.exists()


@pytest.mark.parametrize("args, message", [
    (("--wavelength-pdf-defensive", "0.01"), "needs --wavelength-pdf"),
    (("--wavelength-pdf", "{table}", "--wavelength-pdf-defensive", "1.5"), "share in [0, 1]"),
    (("--wavelength-pdf", "{table}", "--wavelength-pdf-defensive", "nan"), "expected a number"),
    (("--wavelength-pdf", "{table}", "--wavelength-sampling", "uniform"), "give one or the other"),
])
def test_bad_options_are_usage_errors(pbrt, scene, tmp_path, args, message):
    table = str(write_table(tmp_path / "ok.csv", np.ones((4, len(GRID)))))
    run = run_pbrt(pbrt, scene, tmp_path / "never.exr", *(a.format(table=table) for a in args))
    assert run.returncode == 1 and message in run.stderr, run.stderr


def test_help_documents_the_options(pbrt):
    out = subprocess.run([str(pbrt), "--help"], capture_output=True, text=True).stdout
    assert "--wavelength-pdf FILE" in out and "--wavelength-pdf-defensive S" in out
