#!/usr/bin/env bash
# Runs one GDScript test of the Godot plugin headless: assembles a project (the addon, the built library,
# the test scripts) in WORK, runs tests/test_NAME.gd under godot3-server, and fails unless Godot printed
# "GUST_TEST PASS", exited normally and (box) gust's own answer agrees.
# Usage: run_godot_test.sh GODOT3_SERVER LIBRARY WORK NAME REFERENCE
set -euo pipefail
godot="$1" lib="$2" work="$3" name="$4" reference="$5"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
rm -rf "$work" && mkdir -p "$work/project/addons" "$work/home/config" "$work/home/data" "$work/home/cache"
cp -r "$here/../addons/gust" "$work/project/addons/"
mkdir -p "$work/project/addons/gust/bin" && cp "$lib" "$work/project/addons/gust/bin/"
cp "$here/project.godot" "$here"/*.gd "$work/project/"
# godot3-server writes its settings and logs under HOME and the XDG folders.
export HOME="$work/home" XDG_CONFIG_HOME="$work/home/config" XDG_DATA_HOME="$work/home/data" \
  XDG_CACHE_HOME="$work/home/cache" GUST_TEST_OUT="$work/wind.txt" LANG=en_US.UTF-8
# A script error stops a test script before it quits: the timeout ends Godot then.
status=0
timeout 120 "$godot" --path "$work/project" -s "res://test_$name.gd" >"$work/log.txt" 2>&1 || status=$?
cat "$work/log.txt"
if [ $status -ne 0 ]; then
  echo "godot3-server exited with status $status" >&2
  exit 1
fi
if ! grep -q "^GUST_TEST PASS" "$work/log.txt" || grep -q "^GUST_TEST FAIL" "$work/log.txt"; then
  echo "the test script did not pass" >&2
  exit 1
fi
if [ "$name" = errors ]; then
  # The errors must be in Godot's own log, named clearly.
  for expected in "GustWind.cell_size = -1" "is a Spatial, not a MeshInstance" "GustWind.cells.x = 4" \
    "has a Skin but its skeleton path 'nowhere' leads to no Skeleton" "bind 1 follows bone 5"; do
    if ! grep -q "ERROR:.*$expected" "$work/log.txt"; then
      echo "Godot's log lacks an error with \"$expected\"" >&2
      exit 1
    fi
  done
fi
if [ "$name" = box ]; then
  "$reference" "$work/wind.txt"
fi
