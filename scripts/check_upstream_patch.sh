#!/usr/bin/env bash
# Check the wavelength-pdf patch (integrations/pbrt-v4/) on a real upstream pbrt-v4 tree.
#
#   scripts/check_upstream_patch.sh [UPSTREAM_DIR]     (default ../shared/upstream/pbrt-v4)
#
# Copies the tree twice under $UPSTREAM_CHECK_DIR (default ../upstream-check, outside the
# repository): unpatched/ and patched/ (the latter with integrations/pbrt-v4/apply.py applied),
# builds both Release for the CPU (ninja pbrt_exe, -j$JOBS, default 2; ccache when installed,
# with CCACHE_BASEDIR so the patched build reuses the unpatched build's objects), then runs
# scripts/check_upstream_patch.py: (a) bit-identical without the flag, (b) unbiased with a
# table, (c) lower CIEDE2000 at equal spp, (d) the same with --wavefront, (e) a dispersive
# scene, and the uniform/table error ratio beside this repository's build/pbrt.
#
# A second run reuses the copies, the build directories and the renders: only what changed
# is copied, rebuilt or rendered. The first build takes about 20 minutes on 2 cores; this is
# a slow, documented check, not part of scripts/test.sh.
#
# Environment: UPSTREAM_CHECK_DIR, JOBS, PYTHON (a Python with this repository's
# dependencies; default .venv/bin/python), CHECK_ARGS (extra arguments for the .py).
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
UPSTREAM="$(cd "${1:-$REPO/../shared/upstream/pbrt-v4}" 2>/dev/null && pwd)" || {
    echo "check_upstream_patch: ${1:-$REPO/../shared/upstream/pbrt-v4}: no such directory" >&2; exit 2; }
WORK="${UPSTREAM_CHECK_DIR:-$REPO/../upstream-check}"
mkdir -p "$WORK" && WORK="$(cd "$WORK" && pwd)"
JOBS="${JOBS:-2}"
PYTHON="${PYTHON:-$REPO/.venv/bin/python}"
SHARED="$(cd "$UPSTREAM/../.." 2>/dev/null && pwd)"
[ -d "$SHARED/scenes" ] || SHARED="$REPO/../shared"

die() { echo "check_upstream_patch: $*" >&2; exit 2; }
for tool in cmake ninja c++; do command -v "$tool" >/dev/null || die "$tool not found (apt-get install -y cmake ninja-build g++)"; done
[ -f /usr/include/OpenEXR/ImfRgbaFile.h ] || die "OpenEXR headers not found (apt-get install -y libopenexr-dev)"
[ -x "$PYTHON" ] || die "$PYTHON not found (bash scripts/setup.sh makes .venv; or set PYTHON=)"
[ -f "$UPSTREAM/src/pbrt/cmd/pbrt.cpp" ] || die "$UPSTREAM: not a pbrt-v4 source tree"
[ -f "$SHARED/spectra/lspdd/2482.csv" ] || die "$SHARED/spectra/lspdd/2482.csv not found (needs ../shared)"

# Copy UPSTREAM to $1 unless the copy is of the same tree (file list and sizes unchanged).
copy_tree() {
    local dest="$1" stamp
    stamp="$(cd "$UPSTREAM" && find . -type f -printf '%P %s %T@\n' | sort | sha1sum | cut -c1-40)"
    if [ -f "$dest/.upstream-stamp" ] && [ "$(cat "$dest/.upstream-stamp")" = "$stamp" ]; then
        return
    fi
    echo "== copying $UPSTREAM to $dest"
    rm -rf "$dest.tmp" && mkdir -p "$(dirname "$dest")"
    cp -a "$UPSTREAM" "$dest.tmp" && chmod -R u+w "$dest.tmp"
    # Upstream's ptex CMakeLists adds src/build (install rules only); create it when missing.
    if [ -f "$dest.tmp/src/ext/ptex/CMakeLists.txt" ] && [ ! -f "$dest.tmp/src/ext/ptex/src/build/CMakeLists.txt" ]; then
        mkdir -p "$dest.tmp/src/ext/ptex/src/build" && : > "$dest.tmp/src/ext/ptex/src/build/CMakeLists.txt"
    fi
    echo "$stamp" > "$dest.tmp/.upstream-stamp"
    rm -rf "$dest" && mv "$dest.tmp" "$dest"
}

build() {
    local dir="$1"
    mkdir -p "$dir/build"
    local launcher=()
    if command -v ccache >/dev/null; then
        launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    fi
    if [ ! -f "$dir/build/build.ninja" ]; then
        (cd "$dir/build" && cmake -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_DISABLE_FIND_PACKAGE_Git=TRUE \
            -DGLFW_BUILD_X11=OFF -DGLFW_BUILD_WAYLAND=OFF -DBUILD_TESTING=OFF "${launcher[@]}" \
            ../pbrt-v4 > ../cmake.log 2>&1) || { tail -20 "$dir/cmake.log"; die "cmake failed in $dir/build"; }
    fi
    echo "== building $dir/build/pbrt (ninja -j$JOBS pbrt_exe)"
    # CCACHE_BASEDIR makes the compiler's paths relative, so the two copies share cache hits.
    (cd "$dir/build" && CCACHE_BASEDIR="$WORK" CCACHE_NOHASHDIR=1 ninja -j"$JOBS" pbrt_exe > ../ninja.log 2>&1) \
        || { tail -40 "$dir/ninja.log"; die "build failed in $dir/build (log: $dir/ninja.log)"; }
    tail -1 "$dir/ninja.log"
}

t0=$(date +%s)
copy_tree "$WORK/unpatched/pbrt-v4"
copy_tree "$WORK/patched/pbrt-v4"
echo "== applying the patch to $WORK/patched/pbrt-v4"
"$PYTHON" "$REPO/integrations/pbrt-v4/apply.py" "$WORK/patched/pbrt-v4"
build "$WORK/unpatched"
build "$WORK/patched"
echo "== builds done in $(( $(date +%s) - t0 )) s"

TABLE="$WORK/check/table-2482.csv"
mkdir -p "$WORK/check"
if [ ! -f "$TABLE" ]; then
    echo "== optimizing a table for LSPDD 2482"
    PYTHONPATH="$REPO/optimizer" "$PYTHON" -m wavelength_pdf optimize "$SHARED/spectra/lspdd/2482.csv" -o "$TABLE.tmp.csv"
    mv "$TABLE.tmp.csv" "$TABLE"
fi

REPO_PBRT="$REPO/build/pbrt"
PYTHONPATH="$REPO/optimizer" "$PYTHON" "$REPO/scripts/check_upstream_patch.py" \
    --unpatched "$WORK/unpatched/build/pbrt" --patched "$WORK/patched/build/pbrt" \
    --repo-pbrt "$REPO_PBRT" --table "$TABLE" --shared "$SHARED" --work "$WORK/check" ${CHECK_ARGS:-}
