#!/usr/bin/env bash
# Runs COMMAND inside the Debian unstable root that scripts/install_deps.sh makes for Godot 4, with DIR as its
# working directory (bind-mounted at /gust) and HOME there, so Godot's settings and logs stay in DIR. The
# mounts live in a mount namespace of their own, gone when COMMAND ends; runs in parallel need no cleanup.
# Needs root (chroot, mount), as CI runs.
# Usage: in_root.sh ROOT DIR COMMAND [ARG...]
set -euo pipefail
root="$1" dir="$2"
shift 2
mkdir -p "$dir"
exec unshare --mount --propagation private bash -euc '
root="$1" dir="$2"
shift 2
mount --bind "$dir" "$root/gust"
mount -t proc proc "$root/proc"
mount --rbind /dev "$root/dev"
mount -t tmpfs tmpfs "$root/tmp"
exec chroot "$root" env -i PATH=/usr/bin:/bin HOME=/gust/.home XDG_RUNTIME_DIR=/tmp LANG=C.UTF-8 \
  bash -c "cd /gust && exec \"\$@\"" bash "$@"
' bash "$root" "$dir" "$@"
