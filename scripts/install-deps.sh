#!/usr/bin/env bash
# Installs the Debian 12 packages EvFlow needs, only those missing. Run as root (or with sudo).
set -euo pipefail
PKGS=(cmake g++ make pkg-config
      libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers glslang-tools
      libglfw3-dev libimgui-dev libglm-dev libtinygltf-dev nlohmann-json3-dev libopenimageio-dev libstb-dev
      libhdf5-dev hdf5-filter-plugin-blosc-serial catch2 xvfb xauth clang-format git
      colmap  # camera poses (evflow poses)
      clang-14 libclang-rt-14-dev)  # the last two: libFuzzer, ASan, UBSan (scripts/fuzz.sh)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "evflow: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
