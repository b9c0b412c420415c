#!/usr/bin/env bash
# Configures and builds gust into build/ (Release). Extra arguments go to cmake's configure step.
# The Godot 4 root (install_deps.sh) is made in the background while gust compiles: once it is there the build
# is configured again, which adds the Godot 4 extension, and finished.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_deps.sh" --root-in-background
cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$root/build" --parallel "$(nproc)"
pidfile="$root/build-deps/godot4-root.pid"
if [ -f "$pidfile" ]; then
  tail --pid="$(cat "$pidfile")" -f /dev/null
  rm -f "$pidfile"
  cat "$root/build-deps/godot4-root.log" >&2
  cmake -S "$root" -B "$root/build" >/dev/null
  cmake --build "$root/build" --parallel "$(nproc)"
fi
