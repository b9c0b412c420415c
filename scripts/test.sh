#!/usr/bin/env bash
# Builds everything with warnings as errors and runs every test (validation layer on, lavapipe without a GPU;
# the snapshot and threading tests also under ThreadSanitizer).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGUST_WARNINGS_AS_ERRORS=ON -DGUST_BUILD_TESTS=ON -DGUST_BUILD_BENCH=ON -DGUST_SANITIZE_THREAD=ON
cd "$root/build"
ctest --output-on-failure --parallel 2 --timeout 900
