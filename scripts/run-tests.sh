#!/usr/bin/env bash
# The test command: install what is missing, build, run every test through CTest (Vulkan
# validation layer on, fresh GPU buffers poisoned), then fuzz each file reader briefly. Runs on
# lavapipe when there is no GPU.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/evflow-xdg-$(id -u)}"
mkdir -p -m 700 "$XDG_RUNTIME_DIR"
if [ -f tests/tools/package.json ]; then
  # The Khronos glTF validator (npm) for the export tests.
  (cd tests/tools && { [ -d node_modules/gltf-validator ] || npm ci --no-audit --no-fund --silent || npm install --no-audit --no-fund --silent; })
  export EVF_GLTF_VALIDATOR="$PWD/tests/tools/validate_gltf.mjs"
fi
(cd build && ctest --output-on-failure -j"$(nproc)" --timeout 600)
# A short libFuzzer run of every file reader (ASan + UBSan, build-fuzz/); docs/robustness.md.
bash scripts/fuzz.sh --check "${EVF_FUZZ_RUNS:-2000}"
