#!/usr/bin/env bash
# Renders the documentation images of docs/scenes.md: each evaluation scene of ../shared at a
# reduced resolution, once at low spp and once converged (higher spp), with pbrt-v4's default
# (visible) wavelength sampling and the scene's own maximum depth.
# Usage: scripts/render_scene_docs.sh [pbrt binary] [shared dir]   (about 5 CPU-minutes)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PBRT="${1:-$ROOT/build/pbrt}"
SHARED="${2:-$ROOT/../shared}"
OUT="$ROOT/docs/scenes"
SCALE=0.25      # 1024x1024 -> 256x256, 1280x720 -> 320x180
LOW_SPP=16
CONVERGED_SPP=256
mkdir -p "$OUT"
for scene in cornell-box veach-mis teapot veach-bidir staircase glass-of-water; do
    for kind in low converged; do
        spp=$LOW_SPP; [ "$kind" = converged ] && spp=$CONVERGED_SPP
        echo "== $scene ($kind, $spp spp)"
        "$PBRT" --resolution-scale "$SCALE" --spp "$spp" --seed 1 \
            --outfile "$OUT/$scene-$kind.png" "$SHARED/scenes/$scene/scene-v4.pbrt" 2>&1 |
            grep -v "texture filter" | tail -1
    done
done
