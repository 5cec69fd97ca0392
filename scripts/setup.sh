#!/usr/bin/env bash
# One-time (and incremental) set-up on a Debian machine: system packages, the Python
# virtual environment at .venv/ with the package installed, and the renderer at build/pbrt.
# Safe to run again: each step is skipped when its inputs have not changed.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

log() { printf '\033[1m[setup]\033[0m %s\n' "$*" >&2; }

# --- 1. Debian packages --------------------------------------------------------------
APT_PACKAGES=(
  g++ cmake ninja-build pkg-config git
  python3 python3-venv python3-dev
  libembree-dev libtbb-dev libopenexr-dev libgtest-dev libstb-dev
  coinor-libipopt-dev liblapack-dev libblas-dev
  libllvm19  # Mitsuba 3.9's llvm variants need LLVM >= 15 (wavelength_pdf.mitsuba finds it)
  # The sanitizer and fuzzing build (scripts/fuzz.sh): clang, and libclang-rt-14-dev for
  # the ASan/UBSan runtimes and libFuzzer (-fsanitize=fuzzer); ccache for rebuilds.
  clang libclang-rt-14-dev ccache
)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  log "installing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# --- 2. Python environment -----------------------------------------------------------
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  log "creating .venv with $($PY --version)"
  $PY -m venv .venv
fi
stamp=.venv/.installed-$(sha1sum pyproject.toml | cut -c1-12)
if [ ! -f "$stamp" ]; then
  log "installing the wavelength-pdf package and its dependencies into .venv"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e ".[evaluation,test,ipopt]"  # the suite covers the evaluation and Ipopt too
  rm -f .venv/.installed-*; touch "$stamp"
fi

# --- 3. The renderer -----------------------------------------------------------------
GEN=""; command -v ninja >/dev/null && GEN="-G Ninja"
# The compiler: $CXX when set, else clang++ (installed above), which builds a renderer 1-17%
# faster per scene than GCC 12 does here (docs/performance.md, change 26); any C++17
# compiler works. A build/ configured with another compiler is configured again.
CXX_PATH=$(command -v "${CXX:-clang++}" || command -v c++)
if [ -f build/CMakeCache.txt ] && ! grep -qx "CMAKE_CXX_COMPILER:[A-Z]*=$CXX_PATH" build/CMakeCache.txt; then
  log "the renderer's compiler is now $CXX_PATH: configuring build/ again"
  rm -rf build/CMakeCache.txt build/CMakeFiles
fi
if [ ! -f build/CMakeCache.txt ]; then
  log "configuring the renderer (Release, $CXX_PATH)"
  cmake -S . -B build $GEN -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER="$CXX_PATH" >/dev/null
fi
log "building the renderer (incremental)"
cmake --build build --parallel "$(nproc)"
log "ready: .venv/bin/wavelength-pdf and build/pbrt"
