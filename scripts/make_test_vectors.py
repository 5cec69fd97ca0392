"""Write the cross-language test vectors of the wavelength sampler (design §8.1).

The Python sampler (``wavelength_pdf.sampling``) is the reference: this script builds a table
with awkward features, samples it with that module's public functions only, and writes

- ``vectors-table.csv``: the table, in the commented CSV layout of design §2;
- ``vectors.csv``: one row per u with the four wavelengths lambda_k = F_k^-1(u) [nm] and the
  four mixture densities (1/4) sum_k p_k(lambda_j) [1/nm] that Python computes;
- ``equal-mass-inputs.csv`` and ``equal-mass-tables.csv``: weights q at nodes x with awkward
  features (lines narrower than the 0.01 nm hand-over step, zero stretches, a single segment,
  spikes at the ends and on a node, values spanning the 1e-300 floor, a lamp times
  xbar + ybar + zbar), and the tables ``wavelength_pdf.stratified.equal_mass_table`` (the
  reference of design §1.7) builds from them.

The C++ test ``wavelength_table/tests/wavelength_table_test.cpp`` reads them; the sampler must agree to
1e-5 relative, ``wavelength_table::EqualMassTable`` to 1e-12 (same grid, same densities).
``tests/test_vectors.py`` regenerates every file and checks that they equal the committed
files, so neither side can drift unnoticed.

Usage::

    .venv/bin/python scripts/make_test_vectors.py [--out-dir wavelength_table/tests/data]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from wavelength_pdf import sampling
from wavelength_pdf.precision import float64

REPO = Path(__file__).resolve().parents[1]
DEFAULT_OUT = REPO / "wavelength_table" / "tests" / "data"
TABLE_NAME = "vectors-table.csv"
VECTORS_NAME = "vectors.csv"
VECTORS_HEADER = ("u,lambda0,lambda1,lambda2,lambda3,"
                  "mixture_pdf0,mixture_pdf1,mixture_pdf2,mixture_pdf3")
EQUAL_MASS_INPUTS_NAME = "equal-mass-inputs.csv"
EQUAL_MASS_TABLES_NAME = "equal-mass-tables.csv"
EQUAL_MASS_INPUTS_HEADER = "case,x_nm,q"
EQUAL_MASS_TABLES_HEADER = "case,lambda_nm,pdf0,pdf1,pdf2,pdf3"


def awkward_table() -> tuple[np.ndarray, np.ndarray]:
    """Grid [nm] and four (normalized) densities with the features that break samplers.

    - an irregular grid, with a 0.05 nm spacing around 546 nm;
    - pdf0 positive everywhere (so the mixture is never zero), with a nearly flat segment
      (relative slope 1e-11) and a steep one;
    - pdf1 exactly zero on two tails ([380, 420] and [640, 780]);
    - pdf2 a narrow spike (0.1 nm wide) and a bump, exactly zero elsewhere, so its CDF is
      flat on an interior stretch;
    - pdf3 exactly zero on an interior gap [480, 520], rising from zero after it and falling
      to zero at the right end.
    """
    grid = np.array([380.0, 383.7, 395.0, 420.0, 451.3, 480.0, 500.0, 520.0, 545.95, 546.0,
                     546.05, 560.0, 575.0, 590.0, 611.0, 640.0, 700.0, 735.5, 780.0])
    P = np.array([
        [1.0, 1.2, 2.0, 2.0 * (1 + 1e-11), 0.5, 0.5, 3.0, 0.1, 0.4, 0.4, 0.4, 0.7, 0.7,
         0.7, 1.5, 1.0, 1.0, 0.3, 0.05],
        [0.0, 0.0, 0.0, 0.0, 0.8, 1.3, 1.1, 0.9, 2.5, 4.0, 2.5, 1.0, 0.6, 0.6, 0.2, 0.0,
         0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 900.0, 0.0, 0.0, 0.0, 0.0, 5.0, 0.0,
         0.0, 0.0, 0.0],
        [2.0, 2.0, 2.0, 1.0, 0.5, 0.0, 0.0, 0.0, 0.3, 0.3, 0.3, 1.0, 1.0 + 1e-12, 1.0, 0.4,
         0.9, 0.6, 0.2, 0.0],
    ])
    pdfs = np.stack([np.asarray(sampling.normalize(grid, p)) for p in P])
    return grid, pdfs


def vector_us(grid: np.ndarray, pdfs: np.ndarray) -> np.ndarray:
    """The u of the vectors: the ends, values a rounding error away from them, every node of
    every density's CDF (node-hitting u), and a fixed spread of interior values."""
    special = [0.0, 5e-324, 1e-300, 1e-12, 0.5, 1.0 - 1e-12, float(np.nextafter(1.0, 0.0)), 1.0]
    nodes = np.concatenate([np.asarray(sampling.cdf(grid, p)) for p in pdfs])
    strata = (np.arange(32) + 0.5) / 32
    rng = np.random.default_rng(20240604)
    random = rng.random(24)
    u = np.concatenate([special, nodes, strata, random])
    return np.unique(u)  # sorted, without repeats (many CDFs share 0 and 1)


def equal_mass_cases() -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(what, x, q) inputs of the equal-mass construction (design §1.7) that break it if any
    rule of the construction is done differently."""
    cases = [
        ("a 0.004 nm line holding all the mass: three cuts inside it, steps shortened",
         [380.0, 549.998, 550.0, 550.002, 780.0], [0.0, 0.0, 1.0, 0.0, 0.0]),
        ("a spike on a node between 0.001 nm segments: two cuts on the node, an empty band",
         [380.0, 499.999, 500.0, 500.001, 780.0], [0.0, 0.0, 1.0, 0.0, 0.0]),
        ("zero tails and an interior zero stretch, steep 0.02 nm and 0.01 nm edges",
         [380.0, 420.0, 420.02, 430.0, 480.0, 480.5, 520.0, 600.0, 600.01, 700.0, 780.0],
         [0.0, 0.0, 2.0, 2.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]),
        ("a single flat segment (stratified uniform)", [380.0, 780.0], [1.0, 1.0]),
        ("a single rising segment (cuts on a quadratic)", [360.0, 830.0], [0.0, 2.0]),
        ("a spike at the left end holding 85 % of the mass",
         [380.0, 380.004, 500.0, 780.0], [1e6, 0.0, 1.0, 1.0]),
        ("a spike at the right end", [380.0, 600.0, 779.997, 780.0], [1.0, 1.0, 0.0, 4e5]),
        ("values across the 1e-300 floor, scaled from a 1e300 peak",
         [380.0, 400.0, 420.0, 440.0, 460.0, 480.0], [1e300, 1e-10, 1e-310, 0.0, 3e299, 2e290]),
        ("cuts on nodes of a staircase", [380.0, 480.0, 580.0, 680.0, 780.0],
         [1.0, 1.0, 1.0, 1.0, 1.0]),
    ]
    out = [(what, np.asarray(x, dtype=np.float64), np.asarray(q, dtype=np.float64))
           for what, x, q in cases]
    # A lamp of lines on a continuum times xbar + ybar + zbar on 360-830 nm, as the renderer's
    # emission sampling builds it (design §1.7: the union of the spectrum's and the CMFs' nodes).
    from wavelength_pdf.spectra import read_spd
    from wavelength_pdf.stratified import weighted_spectrum

    lamp = read_spd(REPO / "spectra" / "tri-band-fluorescent.spd", lo=None, hi=None)
    x, q = weighted_spectrum(lamp, "xyz", 360.0, 830.0)
    out.append(("the tri-band lamp times xbar + ybar + zbar on 360-830 nm", x, q))
    return out


def write_equal_mass_vectors(out_dir: Path) -> tuple[Path, Path]:
    """Write ``equal-mass-inputs.csv`` and ``equal-mass-tables.csv``; return their paths."""
    from wavelength_pdf.stratified import equal_mass_table

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    head = ["# Test vectors of the equal-mass construction (design §1.7), written by",
            "# scripts/make_test_vectors.py from python/wavelength_pdf/stratified.py (the",
            "# reference). Do not edit by hand."]
    inputs = [*head, "# Weights q at nodes x [nm], linear between them; one case per number:"]
    tables = [*head, f"# The tables equal_mass_table(x, q) builds from {EQUAL_MASS_INPUTS_NAME}:",
              "# grid [nm] and four normalized densities [1/nm] per case."]
    cases = equal_mass_cases()
    inputs += [f"#   {c}: {what}" for c, (what, _, _) in enumerate(cases)]
    inputs.append(EQUAL_MASS_INPUTS_HEADER)
    tables.append(EQUAL_MASS_TABLES_HEADER)
    for c, (_, x, q) in enumerate(cases):
        inputs += [f"{c},{float(a)!r},{float(b)!r}" for a, b in zip(x, q)]
        t = equal_mass_table(x, q)
        for i in range(t.grid.size):
            tables.append(",".join([str(c)] + [repr(float(v)) for v in (t.grid[i], *t.pdfs[:, i])]))
    paths = out_dir / EQUAL_MASS_INPUTS_NAME, out_dir / EQUAL_MASS_TABLES_NAME
    for path, lines in zip(paths, (inputs, tables)):
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return paths


@float64  # the reference samples in float64 (run as a script, JAX would default to float32)
def write_vectors(out_dir: Path) -> tuple[Path, ...]:
    """Write ``vectors-table.csv``, ``vectors.csv`` and the equal-mass vectors into
    ``out_dir``; return their paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    grid, pdfs = awkward_table()
    table_path = out_dir / TABLE_NAME
    _write_table(table_path, grid, pdfs)

    u = vector_us(grid, pdfs)
    lam = np.asarray(sampling.sample_four(grid, pdfs, u))          # (4, n)
    mix = np.asarray(sampling.mixture_pdf(grid, pdfs, lam))        # (4, n)
    lines = [
        "# Test vectors of the wavelength sampler, written by scripts/make_test_vectors.py",
        "# from python/wavelength_pdf/sampling.py (the reference). Do not edit by hand.",
        f"# Table: {TABLE_NAME}. Columns: u, lambda_k = F_k^-1(u) [nm] (k = 0..3, one u for",
        "# all four), mixture_pdf_j = (1/4) sum_k p_k(lambda_j) [1/nm].",
        VECTORS_HEADER,
    ]
    for i in range(u.size):
        values = [u[i], *lam[:, i], *mix[:, i]]
        lines.append(",".join(repr(float(v)) for v in values))
    vectors_path = out_dir / VECTORS_NAME
    vectors_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return (table_path, vectors_path, *write_equal_mass_vectors(out_dir))


def _write_table(path: Path, grid: np.ndarray, pdfs: np.ndarray) -> None:
    """The table in the design §2 layout, through the package's writer when it has one."""
    comments = ["Awkward table for the cross-language sampler tests",
                "written by scripts/make_test_vectors.py; do not edit by hand"]
    try:
        from wavelength_pdf.table import Table, write_table
    except ImportError:  # the package without its table module: the same layout by hand
        rows = [",".join(repr(float(v)) for v in (grid[i], *pdfs[:, i]))
                for i in range(grid.size)]
        text = "".join(f"# {c}\n" for c in comments) + "lambda_nm,pdf0,pdf1,pdf2,pdf3\n"
        path.write_text(text + "\n".join(rows) + "\n", encoding="utf-8")
        return
    write_table(path, Table(grid=grid, pdfs=pdfs, comments=comments))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out-dir", type=Path, default=DEFAULT_OUT,
                        help=f"where to write {TABLE_NAME}, {VECTORS_NAME} and the "
                             f"equal-mass vectors "
                             f"(default: {DEFAULT_OUT.relative_to(REPO)})")
    args = parser.parse_args(argv)
    for path in write_vectors(args.out_dir):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
