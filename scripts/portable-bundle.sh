#!/usr/bin/env bash
# A self-contained tarball of a build for a Linux x86-64 machine with a Vulkan driver but none of
# Debian's packages (a GPU server's image, say): the binaries of BUILD (default build-stb/, the
# stb build: cmake -DEVFLOW_IMAGE_IO=stb, which needs none of OpenImageIO's ~260 libraries), every
# shared library they load except the C runtime's, the Vulkan loader and the validation layer.
#   bash scripts/portable-bundle.sh [BUILD] [OUT.tar.xz]
# On the other machine, in a checkout's root: tar -xJf OUT.tar.xz && source .portable/env.sh
# (the binaries land at BUILD/evflow and BUILD/tests/evflow_tests, as built).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build-stb}"
out="${2:-portable.tar.xz}"
[ -x "$build/evflow" ] || { echo "$build/evflow: not built" >&2; exit 1; }
stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/.portable/lib" "$stage/.portable/layer" "$stage/$build/tests"
cp "$build/evflow" "$stage/$build/"
[ -x "$build/tests/evflow_tests" ] && cp "$build/tests/evflow_tests" "$stage/$build/tests/"
# The C runtime (glibc, libstdc++, libgcc) is the host's own: newer there than here is fine.
runtime='^(linux-vdso|ld-linux|libc|libm|libdl|libpthread|librt|libresolv|libstdc\+\+|libgcc_s)\.'
for bin in "$stage/$build/evflow" "$stage/$build/tests/evflow_tests"; do
  [ -f "$bin" ] || continue  # a build of the CLI alone has no test binary
  ldd "$bin" | awk '$3 ~ /^\// {print $1, $3}'
done | sort -u | while read -r name path; do
  [[ "$name" =~ $runtime ]] || cp -L "$path" "$stage/.portable/lib/$name"
done
layer=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
if [ -f "$layer" ]; then
  cp "$layer" "$stage/.portable/layer/"
  cp -L /usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so "$stage/.portable/layer/"
fi
cat >"$stage/.portable/env.sh" <<'ENV'
# Sourced in the checkout's root after unpacking: the bundled libraries and layer, and the
# NVIDIA driver's Vulkan manifest where the loader would not find it by itself.
here="$PWD/.portable"
export LD_LIBRARY_PATH="$here/lib:$here/layer${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export VK_LAYER_PATH="$here/layer"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/evflow-xdg-$(id -u)}"
mkdir -p -m 700 "$XDG_RUNTIME_DIR"
for icd in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.json; do
  if [ -f "$icd" ] && [ -z "${VK_DRIVER_FILES:-}" ]; then export VK_DRIVER_FILES="$icd" VK_ICD_FILENAMES="$icd"; fi
done
ENV
tar -C "$stage" -cJf "$out" .portable "$build"
echo "$out: $(du -h "$out" | cut -f1) ($(ls "$stage/.portable/lib" | wc -l) libraries)"
