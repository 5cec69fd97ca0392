"""Write the edge-case tables of tests/data/tables/edge/ (design §2, §2.3).

Every table reader (the Python reader, the C++ header, the renderer) is tested on these
same files against tests/data/tables/edge/expected.csv, so that the readers agree on what a
line is, which characters a table may hold, what a number is, and how densities at the
extremes of double precision are renormalized. Run from the repository root:

    python scripts/make_edge_tables.py

The files are written byte for byte (no newline translation); .gitattributes keeps git
from changing their line ends. The expectations are written here too, beside the files they
describe: expected.csv (each file's outcome: accepted with so many nodes, or refused at a
line for a reason) and same.csv (pairs of accepted files that must read as the same table;
the *-normalized.csv files hold the exact renormalized densities, rounded once).
"""
from __future__ import annotations

from fractions import Fraction
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "tables" / "edge"
HEADER = "lambda_nm,pdf0,pdf1,pdf2,pdf3\n"

EXPECTED_HEADER = """\
# The tables of this folder and what every table reader must make of them (design §2, §2.3):
# the Python reader (wavelength_pdf.table.read_table: optimizer, show, Mitsuba plugin), the
# header (wavelength_table::LoadTable) and the renderer (pbrt --wavelength-pdf) read the same
# files here and must agree. A row with `nodes` is a table that is accepted with that many
# grid nodes (each density then integrates to 1); a row with `line` and `reason` is refused
# with the message "FILE:LINE: ..." containing the reason. scripts/make_edge_tables.py
# writes the files and this list.
file,nodes,line,reason
"""

SAME_HEADER = """\
# Pairs of accepted tables of this folder that every table reader must read as the same
# table: the same grid, and densities equal to rounding (design §2.1a, §2.2, §2.3). A
# *-normalized.csv file holds the exact renormalized densities of its pair, each rounded
# once to the nearest double (computed in rational numbers by scripts/make_edge_tables.py,
# which writes this list), so the readers agree on the numbers, not only with each other.
file,same_as
"""


def rows(grid: list[float], values) -> str:
    return "".join(f"{g!r},{','.join(values(i))}\n" for i, g in enumerate(grid))


def wide(values: list[list[str]], trailing: str = ",") -> str:
    """The headerless 4 x 81 layout (rows of densities, with the trailing commas of the files
    of Dobos 2025)."""
    return "".join(",".join(row) + trailing + "\n" for row in values)


def wide_values() -> list[list[str]]:
    """Positive densities on the 4 x 81 grid, not normalized."""
    return [[repr(1.0 + k + 0.25 * ((i * (k + 1)) % 7)) for i in range(81)] for k in range(4)]


def normalized(grid: list[str], values: list[list[str]]) -> str:
    """The table of ``grid`` and ``values`` (as written) in the column layout, each density
    divided by its exact trapezoid mass, rounded once: what a reader should get."""
    x = [Fraction(g) for g in grid]
    out = []
    for row in values:
        v = [Fraction(a) for a in row]
        mass = sum((v[i] + v[i + 1]) * (x[i + 1] - x[i]) / 2 for i in range(len(x) - 1))
        out.append([repr(float(a / mass)) for a in v])
    return ("# exact renormalized densities\n" + HEADER
            + "".join(f"{g},{','.join(out[k][i] for k in range(4))}\n"
                      for i, g in enumerate(grid)))


def main() -> None:
    files: dict[str, str | bytes] = {}
    expected: list[tuple[str, str, str, str]] = []  # file, nodes, line, reason
    same: list[tuple[str, str]] = []  # file, same_as

    def accepted(name: str, nodes: int) -> None:
        expected.append((name, str(nodes), "", ""))

    def refused(name: str, content: str, line: int, reason: str) -> None:
        files[name] = content
        expected.append((name, "", str(line), reason))
    # Subnormal densities on an irregular grid (steps 1.3 and 0.6 nm): each segment's area,
    # computed in subnormal numbers, rounds to a whole multiple of the smallest double.
    grid = [380.0]
    for i in range(200):
        grid.append(round(grid[-1] + (1.3 if i % 2 == 0 else 0.6), 10))
    files["denormal.csv"] = ("# every density 5e-324 (the smallest subnormal double)\n" + HEADER
                             + rows(grid, lambda i: ["5e-324"] * 4))
    accepted("denormal.csv", 201)

    def triangle(i: int) -> str:
        return f"{min(i, 200 - i) * 5e-324:.17g}"

    files["denormal-shaped.csv"] = (
        "# subnormal densities with a shape, beside a normal one\n" + HEADER
        + rows(grid, lambda i: [triangle(i), "0.25", triangle(i), repr((i % 7) * 5e-324)]))
    accepted("denormal-shaped.csv", 201)
    files["huge.csv"] = ("# densities near the largest double\n" + HEADER
                         + rows([380.0, 580.0, 780.0], lambda i: ["1e308", "1.7e308", "1e300", "1"]))
    accepted("huge.csv", 3)
    # Grids at the ends of double precision: a mass that overflows, one below the normals.
    refused("grid-too-wide.csv", HEADER + "-1e308,1,1,1,1\n1e308,1,1,1,1\n", 2,
            "pdf0 integrates to infinity (the grid is too wide)")
    refused("grid-too-narrow.csv", HEADER + "0,1,1,1,1\n5e-324,1,1,1,1\n", 2,
            "pdf0 cannot be normalized exactly (the grid is too narrow)")

    # Line ends: LF, CR LF and a lone CR, mixed; a byte-order mark, tabs and spaces.
    ok = HEADER + "380,1,2,3,4\n580,1,2,3,4\n780,1,2,3,4\n"
    files["crlf.csv"] = ok.replace("\n", "\r\n")
    files["cr.csv"] = ok.replace("\n", "\r")
    files["mixed-line-ends.csv"] = ("# LF\r\n" + HEADER.rstrip("\n") + "\r380,1,2,3,4\n"
                                    "580,1,2,3,4\r\n780,1,2,3,4")
    files["bom-tabs-spaces.csv"] = ("\ufeff# a byte-order mark, tabs and spaces\n" + HEADER
                                    + "380 ,\t1, 2 ,3,4,\n\t580,1,2,3,4\n780,1,2,3,4 \n")
    for name in ("crlf.csv", "cr.csv", "mixed-line-ends.csv", "bom-tabs-spaces.csv"):
        accepted(name, 3)

    # Control characters: not line ends, not white space, an error wherever they are.
    bad = HEADER + "380,1,2,3,4\n580,1,2{c},3,4\n780,1,2,3,4\n"
    for name, c in (("form-feed", "\f"), ("vertical-tab", "\v"), ("nul", "\0"),
                    ("escape", "\x1b"), ("delete", "\x7f"), ("nel", "\u0085")):
        refused(f"{name}.csv", bad.format(c=c), 3, f"control character U+{ord(c):04X}")
    refused("form-feed-row-end.csv", HEADER + "380,1,2,3,4\f\n580,1,2,3,4\n780,1,2,3,4\n", 2,
            "control character U+000C")
    refused("form-feed-in-comment.csv", "# a comment\f380,1,1,1,1\n" + ok, 1,
            "control character U+000C")
    refused("nel-between-rows.csv", HEADER + "380,1,2,3,4\u0085580,1,2,3,4\n780,1,2,3,4\n", 2,
            "control character U+0085")

    # Text that Python alone would take for a line end, white space or a number.
    for name, line, text in (
            ("line-separator.csv", 2, "380,1,2,3,4\u2028\n580,1,2,3,4\n780,1,2,3,4\n"),
            ("no-break-space.csv", 3, "380,1,2,3,4\n580,\u00a01,2,3,4\n780,1,2,3,4\n"),
            ("arabic-digits.csv", 3, "380,1,2,3,4\n580,1,\u0661\u0662,3,4\n780,1,2,3,4\n"),
            ("underscore.csv", 3, "380,1,2,3,4\n580,1,1_000,3,4\n780,1,2,3,4\n"),
            ("nan-payload.csv", 3, "380,1,2,3,4\n580,1,nan(1),3,4\n780,1,2,3,4\n")):
        refused(name, HEADER + text, line, "cannot parse number")
    # Bytes that are not UTF-8: harmless in a comment, not a number in a row.
    files["latin1-bytes.csv"] = (b"# caf\xe9 (Latin-1)\n" + ok.encode()
                                 + b"780.5,1,2\x85,3,4\n")
    expected.append(("latin1-bytes.csv", "", "6", "cannot parse number"))

    # Every reject class of design §2.3, with the line a reader names (rows start at line 3).
    h = "# comment\n" + HEADER
    for name, text, line, reason in (
            ("nan.csv", "380,1,1,1,1\n390,1,nan,1,1\n", 4, "pdf1 is NaN at 390 nm"),
            ("nan-upper.csv", "380,1,1,1,NaN\n390,1,1,1,1\n", 3, "pdf3 is NaN at 380 nm"),
            ("inf.csv", "380,1,1,1,1\n390,1,1,1,1\n400,inf,1,1,1\n", 5,
             "pdf0 is infinite at 400 nm"),
            ("minus-inf.csv", "380,1,1,-Infinity,1\n390,1,1,1,1\n", 3,
             "pdf2 is infinite at 380 nm"),
            ("overflow.csv", "380,1,1,1,1\n390,1,1e400,1,1\n", 4, "pdf1 is infinite at 390 nm"),
            ("negative.csv", "380,1,1,1,1\n390,1,1,-0.5,1\n", 4,
             "pdf2 is negative (-0.5) at 390 nm"),
            ("grid-nan.csv", "380,1,1,1,1\nnan,1,1,1,1\n", 4, "wavelength is nan (must be finite)"),
            ("zero.csv", "380,1,0,1,1\n390,1,0,1,1\n400,1,0,1,1\n", 3, "pdf1 is zero everywhere"),
            ("negative-zero.csv", "380,1,1,0,1\n390,1,1,-0,1\n", 3, "pdf2 is zero everywhere"),
            ("repeated.csv", "380,1,1,1,1\n390,1,1,1,1\n390,1,1,1,1\n", 5,
             "grid is not strictly increasing (390 then 390 nm)"),
            ("repeated-decimal.csv", "546.1,1,1,1,1\n546.1,1,1,1,1\n", 4,
             "grid is not strictly increasing (546.1 then 546.1 nm)"),
            ("decreasing.csv", "380,1,1,1,1\n400,1,1,1,1\n390,1,1,1,1\n", 5,
             "grid is not strictly increasing (400 then 390 nm)"),
            ("four-columns.csv", "380,1,1,1,1\n390,1,1,1\n", 4, "4 columns, expected 5"),
            ("six-columns.csv", "380,1,1,1,1,1\n390,1,1,1,1\n", 3, "6 columns, expected 5"),
            ("one-node.csv", "380,1,1,1,1\n", 3, "a table needs at least 2 grid nodes, got 1"),
            ("header-only.csv", "", 2, "no data rows"),
            ("text.csv", "380,1,1,1,1\n390,1,abc,1,1\n", 4, "cannot parse number 'abc'"),
            ("garbage.csv", "380,1,1,1,1\n390,1,1.5x,1,1\n", 4, "cannot parse number '1.5x'"),
            ("empty-field.csv", "380,1,1,1,1\n390,1,,1,1\n", 4, "cannot parse number ''"),
            ("second-header.csv", "380,1,1,1,1\n" + HEADER, 4,
             "cannot parse number 'lambda_nm'")):
        refused(name, h + text, line, reason)
    refused("header-columns.csv", "lambda_nm,pdf0,pdf1,pdf2\n380,1,1,1\n", 1,
            "header has 4 columns, expected 5")
    refused("empty.csv", "", 1, "no data rows")
    refused("comments-only.csv", "# a\n# b\n# c\n", 3, "no data rows")

    # The same classes in the headerless 4 x 81 layout, and its own: rows of the wrong
    # length (shapes are checked before numbers) and the wrong number of rows.
    def wide_with(k: int, i: int, value: str) -> list[list[str]]:
        v = wide_values()
        v[k][i] = value
        return v

    refused("wide-negative.csv", "# a 4 x 81 table\n" + wide(wide_with(2, 40, "-1")), 4,
            "pdf2 is negative (-1) at 580 nm")
    refused("wide-nan.csv", wide(wide_with(3, 0, "nan")), 4, "pdf3 is NaN at 380 nm")
    refused("wide-zero.csv", wide(wide_values()[:3] + [["0"] * 81]), 4, "pdf3 is zero everywhere")
    short = wide_values()
    short[2].pop()
    refused("wide-ragged-short.csv", wide(short), 3, "80 densities, expected 81")
    long = wide_values()
    long[1].append("1.0")
    refused("wide-ragged-long.csv", "# c\n" + wide(long), 3, "82 densities, expected 81")
    refused("wide-three-rows.csv", wide(wide_values()[:3]), 3, "3 rows of densities, expected 4")
    refused("wide-five-rows.csv", wide(wide_values() + wide_values()[:1]), 4,
            "5 rows of densities, expected 4")

    # Tables that read as the same table: every line end, blanks and a byte-order mark as the
    # plain file; both layouts; and a table beside its exact renormalization.
    files["plain.csv"] = ok
    accepted("plain.csv", 3)
    for name in ("crlf.csv", "cr.csv", "mixed-line-ends.csv", "bom-tabs-spaces.csv"):
        same.append((name, "plain.csv"))
    wide_grid = [repr(380.0 + 5.0 * i) for i in range(81)]
    files["layout-4x81.csv"] = wide(wide_values())
    files["layout-columns.csv"] = "# the same densities in columns\n" + HEADER + "".join(
        f"{g},{','.join(row[i] for row in wide_values())}\n" for i, g in enumerate(wide_grid))
    files["layout-normalized.csv"] = normalized(wide_grid, wide_values())
    # An irregular grid with exact zeros, a spike and values of very different sizes.
    grid = ["380", "381.5", "450.25", "546.07", "546.08", "600", "700.125", "780"]
    values = [["1", "2", "3", "4", "5", "6", "7", "8"],
              ["0", "0", "1e-3", "400", "0.5", "0", "0", "0"],
              ["5", "4", "0", "0", "0", "0", "2.5", "1e6"],
              ["3e-200", "1e-200", "0", "2e-200", "0", "0", "7e-200", "0"]]
    files["varied.csv"] = "# irregular\n" + HEADER + "".join(
        f"{g},{','.join(row[i] for row in values)}\n" for i, g in enumerate(grid))
    files["varied-normalized.csv"] = normalized(grid, values)
    for name, nodes in (("layout-4x81.csv", 81), ("layout-columns.csv", 81),
                        ("layout-normalized.csv", 81), ("varied.csv", 8),
                        ("varied-normalized.csv", 8)):
        accepted(name, nodes)
    same += [("layout-4x81.csv", "layout-columns.csv"),
             ("layout-columns.csv", "layout-normalized.csv"),
             ("varied.csv", "varied-normalized.csv")]

    OUT.mkdir(parents=True, exist_ok=True)
    for name, content in files.items():
        data = content if isinstance(content, bytes) else content.encode("utf-8")
        (OUT / name).write_bytes(data)
    assert sorted(f for f, *_ in expected) == sorted(files), "one expectation per file"
    (OUT / "expected.csv").write_text(
        EXPECTED_HEADER + "".join(",".join(row) + "\n" for row in expected), encoding="utf-8")
    (OUT / "same.csv").write_text(
        SAME_HEADER + "".join(",".join(row) + "\n" for row in same), encoding="utf-8")
    print(f"wrote {len(files)} tables to {OUT}")


if __name__ == "__main__":
    main()
