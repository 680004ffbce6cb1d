#!/usr/bin/env bash
# The main job on the embedded default data: install what is missing, build, then run the
# pipeline into runs/main/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/evflow-xdg-$(id -u)}"
mkdir -p -m 700 "$XDG_RUNTIME_DIR"
OUT=runs/main
mkdir -p "$OUT"
build/evflow devices
build/evflow fit-demo --out "$OUT/fit-demo"
build/evflow bench raster --gaussians 100000 --repeats 3 --json | tee "$OUT/bench_raster.json"
