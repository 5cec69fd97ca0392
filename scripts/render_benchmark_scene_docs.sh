#!/usr/bin/env bash
# Renders the documentation images of the benchmark scenes (docs/scenes.md, "The benchmark's
# own scenes"): each scene of scenes/benchmark at half its film size with pbrt-v4's default
# (visible) wavelength sampling, and ../shared's glass of water with the project's water body
# (wavelength_pdf.evaluation.glass_of_water) at 0.15 of its size (PNGs are stored uncompressed).
# Usage: scripts/render_benchmark_scene_docs.sh [pbrt binary] [shared dir]
#        (PYTHON: the interpreter with colour-science and numpy, default .venv/bin/python;
#        about 4 CPU-minutes)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PBRT="${1:-$ROOT/build/pbrt}"
SHARED="${2:-$ROOT/../shared}"
PYTHON="${PYTHON:-$ROOT/.venv/bin/python}"
OUT="$ROOT/docs/scenes"
mkdir -p "$OUT"
for scene in colorchecker lamp-room prism tinted-glass window-room night-street; do
    spp=256; [ "$scene" = prism ] && spp=1024
    echo "== $scene ($spp spp)"
    "$PBRT" --quiet --resolution-scale 0.5 --spp "$spp" --seed 1 \
        --outfile "$OUT/benchmark-$scene.png" "$ROOT/scenes/benchmark/$scene/scene.pbrt"
done
if [ -f "$SHARED/scenes/glass-of-water/scene-v4.pbrt" ]; then
    echo "== glass-of-water with water (256 spp)"
    TMP="$(mktemp -d)"
    trap 'rm -rf "$TMP"' EXIT
    PYTHONPATH="$ROOT/optimizer${PYTHONPATH:+:$PYTHONPATH}" "$PYTHON" -c \
        "import sys; from wavelength_pdf.evaluation.glass_of_water import with_water; with_water(sys.argv[1], sys.argv[2], resolution=0.15)" \
        "$SHARED/scenes/glass-of-water/scene-v4.pbrt" "$TMP/scene.pbrt"
    "$PBRT" --quiet --spp 256 --seed 1 --outfile "$OUT/benchmark-glass-of-water-with-water.png" "$TMP/scene.pbrt" 2>&1 |
        grep -v 'Integrator "bdpt" is not supported' || true
fi
