#!/usr/bin/env bash
# Held-out quality of point3d.ply sampled over the scene's time (datagen now, issue 56) against
# the cloud datagen wrote before (every point sampled at t = 0 and carrying t = 0), the renders
# the same: for each SCENE of MINI (datagen scenes), a copy whose point3d.ply is replaced by the
# t = 0 cloud (point3d_at_t0.py: datagen's script version 1 sampling, same seed and point count),
# then `hdr4d train --iterations ITERATIONS --threads THREADS` (default flags, seed 0) on both,
# one training at a time. Prints held-out LDR PSNR and aligned mu-PSNR, t = 0 / over time.
#   bash benchmark/proofs/point3d_over_time.sh BINARY MINI WORKDIR SCENE...
# MINI: the folder of `hdr4d datagen --preset mini --scene all` (never written). WORKDIR keeps
# the copies and runs; a run already finished there is not trained again.
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 BINARY MINI WORKDIR SCENE..." >&2
  exit 2
fi
hdr4d="$(realpath "$1")" mini="$2" work="$3"
shift 3
iterations="${ITERATIONS:-2000}" threads="${THREADS:-2}"
here="$(cd "$(dirname "$0")" && pwd)"
scripts="$(cd "$here/../../datagen/blender" && pwd)"
mkdir -p "$work"
train() {  # SCENE_DIR RUN
  [ -f "$2/results.json" ] && return 0
  /usr/bin/time -f "%U %S %e" -o "$2.time" nice -n 10 "$hdr4d" train --data "$1" --out "$2" \
    --iterations "$iterations" --threads "$threads" --overwrite > "$2.log" 2>&1
}
for scene in "$@"; do
  src="$mini/$scene" copy="$work/${scene}_t0"
  [ -f "$src/point3d.ply" ] || { echo "$0: $src/point3d.ply: missing" >&2; exit 1; }
  if [ ! -f "$copy/point3d.ply.done" ]; then
    rm -rf "$copy"
    cp -r "$src" "$copy"
    read -r seed points < <(python3 -c "import json,sys; m=json.load(open(sys.argv[1])); \
print(m['seed'], m['points']['count'])" "$src/manifest.json")
    nice -n 10 blender -b --factory-startup --python-exit-code 1 -P "$here/point3d_at_t0.py" -- \
      --scripts "$scripts" --scene "$scene" --seed "$seed" --points "$points" \
      --out "$copy/point3d.ply" > "$copy.blender.log" 2>&1
    touch "$copy/point3d.ply.done"
  fi
  train "$src" "$work/${scene}_time"
  train "$copy" "$work/${scene}_t0run"
done
python3 - "$work" "$@" <<'PY'
import json, sys
work, scenes = sys.argv[1], sys.argv[2:]
rows, sums = [], [0.0] * 4
for s in scenes:
    t0 = json.load(open(f"{work}/{s}_t0run/results.json"))["test"]
    tt = json.load(open(f"{work}/{s}_time/results.json"))["test"]
    v = [t0["psnr"], tt["psnr"], t0.get("mu_psnr_aligned", float("nan")), tt.get("mu_psnr_aligned", float("nan"))]
    sums = [a + b for a, b in zip(sums, v)]
    print(f"{s:8s} LDR PSNR t=0 {v[0]:.2f} / over time {v[1]:.2f} ({v[1]-v[0]:+.2f})   "
          f"aligned mu-PSNR {v[2]:.2f} / {v[3]:.2f} ({v[3]-v[2]:+.2f})")
n = len(scenes)
m = [x / n for x in sums]
print(f"{'mean':8s} LDR PSNR t=0 {m[0]:.2f} / over time {m[1]:.2f} ({m[1]-m[0]:+.2f})   "
      f"aligned mu-PSNR {m[2]:.2f} / {m[3]:.2f} ({m[3]-m[2]:+.2f})")
PY
