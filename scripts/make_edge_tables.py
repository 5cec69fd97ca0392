"""Write the edge-case tables of tests/data/tables/edge/ (design §2, §2.3).

Every table reader (the Python reader, the C++ header, the renderer) is tested on these
same files against tests/data/tables/edge/expected.csv, so that the readers agree on what a
line is, which characters a table may hold, what a number is, and how densities at the
extremes of double precision are renormalized. Run from the repository root:

    python scripts/make_edge_tables.py

The files are written byte for byte (no newline translation); .gitattributes keeps git
from changing their line ends.
"""
from __future__ import annotations

from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "tables" / "edge"
HEADER = "lambda_nm,pdf0,pdf1,pdf2,pdf3\n"


def rows(grid: list[float], values) -> str:
    return "".join(f"{g!r},{','.join(values(i))}\n" for i, g in enumerate(grid))


def main() -> None:
    files: dict[str, str | bytes] = {}
    # Subnormal densities on an irregular grid (steps 1.3 and 0.6 nm): each segment's area,
    # computed in subnormal numbers, rounds to a whole multiple of the smallest double.
    grid = [380.0]
    for i in range(200):
        grid.append(round(grid[-1] + (1.3 if i % 2 == 0 else 0.6), 10))
    files["denormal.csv"] = ("# every density 5e-324 (the smallest subnormal double)\n" + HEADER
                             + rows(grid, lambda i: ["5e-324"] * 4))

    def triangle(i: int) -> str:
        return f"{min(i, 200 - i) * 5e-324:.17g}"

    files["denormal-shaped.csv"] = (
        "# subnormal densities with a shape, beside a normal one\n" + HEADER
        + rows(grid, lambda i: [triangle(i), "0.25", triangle(i), repr((i % 7) * 5e-324)]))
    files["huge.csv"] = ("# densities near the largest double\n" + HEADER
                         + rows([380.0, 580.0, 780.0], lambda i: ["1e308", "1.7e308", "1e300", "1"]))
    # Grids at the ends of double precision: a mass that overflows, one below the normals.
    files["grid-too-wide.csv"] = HEADER + "-1e308,1,1,1,1\n1e308,1,1,1,1\n"
    files["grid-too-narrow.csv"] = HEADER + "0,1,1,1,1\n5e-324,1,1,1,1\n"

    # Line ends: LF, CR LF and a lone CR, mixed; a byte-order mark, tabs and spaces.
    ok = HEADER + "380,1,2,3,4\n580,1,2,3,4\n780,1,2,3,4\n"
    files["crlf.csv"] = ok.replace("\n", "\r\n")
    files["cr.csv"] = ok.replace("\n", "\r")
    files["mixed-line-ends.csv"] = ("# LF\r\n" + HEADER.rstrip("\n") + "\r380,1,2,3,4\n"
                                    "580,1,2,3,4\r\n780,1,2,3,4")
    files["bom-tabs-spaces.csv"] = ("\ufeff# a byte-order mark, tabs and spaces\n" + HEADER
                                    + "380 ,\t1, 2 ,3,4,\n\t580,1,2,3,4\n780,1,2,3,4 \n")

    # Control characters: not line ends, not white space, an error wherever they are.
    bad = HEADER + "380,1,2,3,4\n580,1,2{c},3,4\n780,1,2,3,4\n"
    for name, c in (("form-feed", "\f"), ("vertical-tab", "\v"), ("nul", "\0"),
                    ("escape", "\x1b"), ("delete", "\x7f"), ("nel", "\u0085")):
        files[f"{name}.csv"] = bad.format(c=c)
    files["form-feed-row-end.csv"] = HEADER + "380,1,2,3,4\f\n580,1,2,3,4\n780,1,2,3,4\n"
    files["form-feed-in-comment.csv"] = "# a comment\f380,1,1,1,1\n" + ok
    files["nel-between-rows.csv"] = HEADER + "380,1,2,3,4\u0085580,1,2,3,4\n780,1,2,3,4\n"

    # Text that Python alone would take for a line end, white space or a number.
    files["line-separator.csv"] = HEADER + "380,1,2,3,4\u2028\n580,1,2,3,4\n780,1,2,3,4\n"
    files["no-break-space.csv"] = HEADER + "380,1,2,3,4\n580,\u00a01,2,3,4\n780,1,2,3,4\n"
    files["arabic-digits.csv"] = HEADER + "380,1,2,3,4\n580,1,\u0661\u0662,3,4\n780,1,2,3,4\n"
    files["underscore.csv"] = HEADER + "380,1,2,3,4\n580,1,1_000,3,4\n780,1,2,3,4\n"
    files["nan-payload.csv"] = HEADER + "380,1,2,3,4\n580,1,nan(1),3,4\n780,1,2,3,4\n"
    # Bytes that are not UTF-8: harmless in a comment, not a number in a row.
    files["latin1-bytes.csv"] = (b"# caf\xe9 (Latin-1)\n" + ok.encode()
                                 + b"780.5,1,2\x85,3,4\n")

    OUT.mkdir(parents=True, exist_ok=True)
    for name, content in files.items():
        data = content if isinstance(content, bytes) else content.encode("utf-8")
        (OUT / name).write_bytes(data)
    print(f"wrote {len(files)} tables to {OUT}")


if __name__ == "__main__":
    main()
