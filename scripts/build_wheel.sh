#!/usr/bin/env bash
# Builds the wavelength-pdf wheel from the files git tracks, copied to a temporary folder: an
# untracked, ignored or stale file of the checkout never ships, and the checkout (its build/,
# the renderer's CMake folder, included) is not written to. `--help` for the options.
set -euo pipefail

usage() {
  cat <<'EOF'
Usage: bash scripts/build_wheel.sh [--out DIR] [--with-pbrt PATH] [--no-build-isolation]

Builds wavelength_pdf-VERSION-py3-none-any.whl into dist/ from the files git tracks in this
checkout (their current contents), copied to a temporary folder first, and prints its path.
Install it with its extras, e.g.  pip install "dist/wavelength_pdf-VERSION-py3-none-any.whl[evaluation,mitsuba]"
(extras: mitsuba, ipopt).

Options:
  --out DIR             folder for the wheel (default: dist/ in the checkout); the
                        wavelength_pdf-*.whl files already there are replaced
  --with-pbrt PATH      put the renderer PATH (e.g. build/pbrt) inside the wheel as
                        wavelength_pdf/_bin/pbrt, where the installed `wavelength-pdf` finds it
                        with no configuration. The wheel is then tagged for this platform
                        (py3-none-linux_x86_64) and runs where PATH runs: the same system
                        libraries (Embree, TBB, OpenEXR) and, unless the renderer was configured
                        with -DPBRT_NATIVE=OFF, a CPU like the one that built it
  --no-build-isolation  build with the setuptools and wheel already installed for $PYTHON
                        instead of fresh copies from the package index (offline builds)
  -h, --help            this text

Environment: PYTHON, the Python whose pip builds the wheel (default: python3).
EOF
}

die() { printf 'build_wheel.sh: %s\n' "$*" >&2; exit 2; }

ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=$ROOT/dist
PBRT_BIN=""
ISOLATION=()
while (($#)); do
  case $1 in
    -h|--help) usage; exit 0 ;;
    --out) (($# >= 2)) || die "--out needs a folder"; OUT=$2; shift 2 ;;
    --with-pbrt) (($# >= 2)) || die "--with-pbrt needs the renderer's path (e.g. build/pbrt)"; PBRT_BIN=$2; shift 2 ;;
    --no-build-isolation) ISOLATION=(--no-build-isolation); shift ;;
    *) die "unknown argument: $1 (see --help)" ;;
  esac
done

PY=${PYTHON:-python3}
command -v "$PY" >/dev/null || die "no Python '$PY' (set PYTHON)"
"$PY" -m pip --version >/dev/null 2>&1 ||
  die "'$PY' has no pip: run this inside a virtual environment (python3 -m venv ENV && . ENV/bin/activate) or set PYTHON"
git -C "$ROOT" rev-parse --is-inside-work-tree >/dev/null 2>&1 ||
  die "$ROOT is not a git checkout: this script ships only the files git tracks (elsewhere: pip wheel --no-deps -w dist .)"
VERSION=$(sed -n 's/^version *= *"\([^"]*\)".*/\1/p' "$ROOT/pyproject.toml" | head -n1)
[ -n "$VERSION" ] || die "pyproject.toml: no line 'version = \"X.Y.Z\"'"

CONFIG=()
if [ -n "$PBRT_BIN" ]; then
  [ -f "$PBRT_BIN" ] && [ -x "$PBRT_BIN" ] || die "--with-pbrt $PBRT_BIN: not an executable file (build it: bash scripts/setup.sh)"
  # The package's own renderer, of this version: another pbrt lacks the wavelength options,
  # and one built from older sources would be shipped under the new version.
  banner=$("$PBRT_BIN" --version 2>/dev/null) && [ -n "$banner" ] || die "--with-pbrt $PBRT_BIN: '--version' failed (a missing library?)"
  case $banner in
    "pbrt (wavelength-pdf) $VERSION:"*) ;;
    *) die "--with-pbrt $PBRT_BIN is not this project's renderer $VERSION (it says: ${banner%%$'\n'*}); rebuild it: cmake --build build" ;;
  esac
  # A wheel that carries a binary is no longer for any platform: tag it for this one.
  PLAT=$("$PY" -c 'import sysconfig; print(sysconfig.get_platform())')
  CONFIG=(--config-settings "--build-option=--plat-name=$PLAT")
fi

TMP=$(mktemp -d "${TMPDIR:-/tmp}/wavelength-pdf-wheel.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
SRC=$TMP/src
mkdir -p "$SRC" "$TMP/out"
# Tracked files as they are in the work tree; one deleted there but not yet committed is skipped.
git -C "$ROOT" ls-files -z --cached |
  while IFS= read -r -d '' f; do
    if [ -e "$ROOT/$f" ] || [ -L "$ROOT/$f" ]; then printf '%s\0' "$f"; fi
  done |
  tar -C "$ROOT" --null -T - -cf - | tar -C "$SRC" -xf -
if [ -n "$PBRT_BIN" ]; then
  install -D -m 755 "$PBRT_BIN" "$SRC/python/wavelength_pdf/_bin/pbrt"
fi

"$PY" -m pip wheel --no-deps -q "${ISOLATION[@]}" "${CONFIG[@]}" -w "$TMP/out" "$SRC" >&2
shopt -s nullglob
built=("$TMP"/out/wavelength_pdf-*.whl)
((${#built[@]} == 1)) || die "pip wheel did not write one wavelength_pdf wheel (found ${#built[@]})"
mkdir -p "$OUT"
old=("$OUT"/wavelength_pdf-*.whl)
((${#old[@]} == 0)) || rm -f -- "${old[@]}"
mv -- "${built[0]}" "$OUT/"
OUT=$(cd "$OUT" && pwd)
printf '%s\n' "$OUT/$(basename "${built[0]}")"
