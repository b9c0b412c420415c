#!/usr/bin/env bash
# The main job: builds gust and voxelizes the Stanford bunny, printing the stats line.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGUST_BUILD_TESTS=OFF -DGUST_BUILD_BENCH=OFF
mkdir -p "$root/out"
"$root/build/cli/gust" voxelize "$root/assets/scans/bunny.ply" --res 128 --out "$root/out/bunny.vdb"
echo "wrote $root/out/bunny.vdb" >&2
