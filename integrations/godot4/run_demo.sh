#!/usr/bin/env bash
# Assembles the Godot 4 demo project with the addon and the built library in BUILD/integrations/godot4/demo,
# then runs it in the Godot 4 root (in_root.sh): headless, or with --window in a window under Xvfb with
# Forward+ on lavapipe; --validation turns the Khronos validation layer on. Extra arguments go to the demo
# (main.gd: --frames N, --wind on|off, --screenshot PATH, relative to the demo folder, --check).
# Usage: integrations/godot4/run_demo.sh [--build DIR] [--window] [--validation] [DEMO ARGS...]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$here/../../build"
root="$here/../../build-deps/godot4-root"
display=(godot --headless)
layers=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --window) display=(xvfb-run -a -s "-screen 0 640x360x24" godot --rendering-method forward_plus --audio-driver Dummy); shift ;;
    --validation) layers=(VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation); shift ;;
    *) break ;;
  esac
done
lib="$build/integrations/godot4/bin/libgust_godot4.so"
if [ ! -f "$lib" ]; then
  echo "run_demo.sh: $lib is missing: build the gust_godot4 target first" >&2
  exit 1
fi
work="$build/integrations/godot4/demo"
rm -rf "$work" && mkdir -p "$work/project/addons" "$work/project/.godot"
cp "$here"/demo/* "$work/project/"
cp -r "$here/addons/gust" "$work/project/addons/" && mkdir -p "$work/project/addons/gust/bin" && cp "$lib" "$work/project/addons/gust/bin/"
echo "res://addons/gust/gust.gdextension" >"$work/project/.godot/extension_list.cfg"
exec bash "$here/in_root.sh" "$root" "$work" env "${layers[@]}" "${display[@]}" --path /gust/project --fixed-fps 60 -- "$@"
