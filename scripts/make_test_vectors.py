"""Write the cross-language test vectors of the wavelength sampler (design §8.1).

The Python sampler (``wavelength_pdf.sampling``) is the reference: this script builds a table
with awkward features, samples it with that module's public functions only, and writes

- ``vectors-table.csv``: the table, in the commented CSV layout of design §2;
- ``vectors.csv``: one row per u with the four wavelengths lambda_k = F_k^-1(u) [nm] and the
  four mixture densities (1/4) sum_k p_k(lambda_j) [1/nm] that Python computes.

The C++ test ``patches/tests/wavelength_table_test.cpp`` reads both and must agree to 1e-5
relative; ``tests/test_vectors.py`` regenerates them and checks that they equal the committed
files, so neither side can drift unnoticed.

Usage::

    .venv/bin/python scripts/make_test_vectors.py [--out-dir patches/tests/data]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from wavelength_pdf import sampling

REPO = Path(__file__).resolve().parents[1]
DEFAULT_OUT = REPO / "patches" / "tests" / "data"
TABLE_NAME = "vectors-table.csv"
VECTORS_NAME = "vectors.csv"
VECTORS_HEADER = ("u,lambda0,lambda1,lambda2,lambda3,"
                  "mixture_pdf0,mixture_pdf1,mixture_pdf2,mixture_pdf3")


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


def write_vectors(out_dir: Path) -> tuple[Path, Path]:
    """Write ``vectors-table.csv`` and ``vectors.csv`` into ``out_dir``; return their paths."""
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
        "# from optimizer/wavelength_pdf/sampling.py (the reference). Do not edit by hand.",
        f"# Table: {TABLE_NAME}. Columns: u, lambda_k = F_k^-1(u) [nm] (k = 0..3, one u for",
        "# all four), mixture_pdf_j = (1/4) sum_k p_k(lambda_j) [1/nm].",
        VECTORS_HEADER,
    ]
    for i in range(u.size):
        values = [u[i], *lam[:, i], *mix[:, i]]
        lines.append(",".join(repr(float(v)) for v in values))
    vectors_path = out_dir / VECTORS_NAME
    vectors_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return table_path, vectors_path


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
                        help=f"where to write {TABLE_NAME} and {VECTORS_NAME} "
                             f"(default: {DEFAULT_OUT.relative_to(REPO)})")
    args = parser.parse_args(argv)
    for path in write_vectors(args.out_dir):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
