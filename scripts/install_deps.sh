#!/usr/bin/env bash
# Installs the Debian 12 packages gust needs, only those missing; idempotent. Uses sudo only when not root.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
  glslang-tools glslang-dev spirv-tools
  libglm-dev
  libopenvdb-dev libboost-iostreams-dev libtbb-dev
  libassimp-dev libtinygltf-dev assimp-testmodels
  nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev
  libglfw3-dev libimgui-dev libstb-dev xvfb xauth xdotool
  webp
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "gust: installing ${missing[*]}" >&2
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
