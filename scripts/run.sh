#!/usr/bin/env bash
# The main job: builds gust and its sample game and runs the game: in a window when a display exists,
# otherwise headless, writing PNG frames and stats.jsonl to out/sample/. Extra arguments go to the game
# (gust_sample --help lists them).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGUST_BUILD_TESTS=OFF -DGUST_BUILD_BENCH=OFF
cd "$root"
exec "$root/build/sample_game/gust_sample" "$@"
