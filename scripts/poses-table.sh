#!/usr/bin/env bash
# The pose table of docs/poses.md: each built-in scene simulated at the simulator's defaults, then
# `evflow poses` on EDI frames and on the blurry frames; prints one row per (scene, frames) from
# DIR/<scene>_<frames>/colmap/report.json. Usage: scripts/poses-table.sh [DIR] [THREADS]
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-/tmp/evflow-poses-table}
threads=${2:-2}
mkdir -p "$dir"
for scene in default gallery workshop; do
  [ -f "$dir/$scene/dataset.json" ] || build/evflow simulate --scene "$scene" --out "$dir/$scene" > "$dir/$scene.log"
  for frames in edi blurry; do
    out="$dir/${scene}_$frames"
    rm -rf "$out"
    build/evflow poses "$dir/$scene" --out "$out" --"$frames" --threads "$threads" > "$out.log" 2>&1 || true
    python3 - "$scene" "$frames" "$out/colmap/report.json" <<'PY'
import json, sys
scene, frames, path = sys.argv[1:]
r = json.load(open(path))
e = r.get("vs_input_poses", {})
f = lambda k: "%.3f" % e[k] if k in e else "-"
train = [d for v, d in zip(e.get("views", []), e.get("rot_deg", [])) if v in r.get("train_views", [])]
tr = "%.3f" % (sum(train) / len(train)) if train else "-"
print(f"| {scene} | {frames} | {r['registered']}/{r['views']} | {f('rot_mean_deg')} | {f('rot_max_deg')} | {tr} | "
      f"{f('trans_mean_pct')} | {f('trans_max_pct')} | {f('relative_rot_mean_deg')} | {r['points']} | "
      f"{r['reprojection_px']:.2f} | {r['seconds']:.0f} |")
PY
  done
done
