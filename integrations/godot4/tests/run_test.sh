#!/usr/bin/env bash
# Runs one GDScript test of the Godot 4 extension in the Godot 4 root (in_root.sh): assembles a project (the
# addon, the built library, the test scripts) in WORK, runs tests/test_NAME.gd with a fixed 60 Hz frame,
# headless, or for NAME window_* in a window under Xvfb with Forward+ on lavapipe, and fails unless Godot printed "GUST_TEST PASS", quit with 0, logged no error and no Vulkan
# validation message (gust's device runs with the validation layer), and (box) gust's own answer agrees.
# Usage: run_test.sh ROOT LIBRARY WORK NAME [REFERENCE]
set -euo pipefail
root="$1" lib="$2" work="$3" name="$4" reference="${5:-}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
rm -rf "$work" && mkdir -p "$work/project/addons" "$work/project/.godot"
cp -r "$here/../addons/gust" "$work/project/addons/"
mkdir -p "$work/project/addons/gust/bin" && cp "$lib" "$work/project/addons/gust/bin/"
cp "$here/project.godot" "$here"/*.gd "$work/project/"
# What an import writes: the extensions Godot loads at start.
echo "res://addons/gust/gust.gdextension" >"$work/project/.godot/extension_list.cfg"
# A script error stops a test script before it quits: the timeout ends Godot then.
status=0
display=(--headless)
case "$name" in
  window_*) display=(xvfb-run -a -s "-screen 0 320x240x24" godot --rendering-method forward_plus --audio-driver Dummy) ;;
esac
godot=(godot "${display[@]}")
if [ "${display[0]}" = xvfb-run ]; then godot=("${display[@]}"); fi
timeout 120 bash "$here/../in_root.sh" "$root" "$work" env VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation \
  "${godot[@]}" --path /gust/project --fixed-fps 60 -s "res://test_$name.gd" >"$work/log.txt" 2>&1 || status=$?
cat "$work/log.txt"
if [ $status -ne 0 ]; then
  echo "godot exited with status $status" >&2
  exit 1
fi
if ! grep -q "^GUST_TEST PASS" "$work/log.txt" || grep -q "^GUST_TEST FAIL" "$work/log.txt"; then
  echo "the test script did not pass" >&2
  exit 1
fi
if grep -Eq "ERROR|SCRIPT ERROR|VUID-|Validation (Error|Warning)" "$work/log.txt"; then
  echo "Godot's log holds an error or a validation message" >&2
  exit 1
fi
if [ -n "$reference" ]; then
  # The box scene: the node's 4 voxels a cell and the steps it took.
  "$reference" "$work/wind.txt" 4 "$(cat "$work/steps.txt")"
fi
