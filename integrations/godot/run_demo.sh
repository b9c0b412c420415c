#!/usr/bin/env bash
# Assembles the demo project with the addon and the built library in BUILD/integrations/godot/demo, then
# runs it: headless under godot3-server, or in a window with godot3-runner (--window). Extra arguments go to
# the demo (main.gd: --frames N, --wind on|off, --screenshot PATH, --check).
# Usage: integrations/godot/run_demo.sh [--build DIR] [--window] [DEMO ARGS...]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$here/../../build"
godot=godot3-server
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --window) godot=godot3-runner; shift ;;
    *) break ;;
  esac
done
lib="$build/integrations/godot/bin/libgust_godot.so"
if [ ! -f "$lib" ]; then
  echo "run_demo.sh: $lib is missing: build the gust_godot target first" >&2
  exit 1
fi
project="$build/integrations/godot/demo"
rm -rf "$project" && mkdir -p "$project/addons"
cp "$here"/demo/* "$project/"
cp -r "$here/addons/gust" "$project/addons/" && mkdir -p "$project/addons/gust/bin" && cp "$lib" "$project/addons/gust/bin/"
home="${GUST_GODOT_HOME:-$build/integrations/godot/home}"
mkdir -p "$home/config" "$home/data" "$home/cache"
HOME="$home" XDG_CONFIG_HOME="$home/config" XDG_DATA_HOME="$home/data" XDG_CACHE_HOME="$home/cache" \
  LANG=en_US.UTF-8 exec "$godot" --path "$project" --fixed-fps 60 -- "$@"
