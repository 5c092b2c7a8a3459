#!/usr/bin/env bash
# The grid family's learned background against the reference's fixed one (issue 53): the same
# HDR-HexPlane (or other grid) run with --grid-background fixed and each other model, per scene
# and seed; held-out LDR PSNR and the HDR metrics from results.json, CPU time from /usr/bin/time.
# Resumable: a run with a results.json is skipped.
# Usage: bash benchmark/proofs/hexplane_background_ab.sh BINARY WORKDIR SCENE_DIR...
# Settings from the environment: METHOD [hdr-hexplane], SUPERVISION [ldr+hdr], MODELS ["fixed
# environment"], SEEDS ["0 1"], ITERATIONS [300], RAYS [512], GRID ["32768 262144"], THREADS [2].
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 BINARY WORKDIR SCENE_DIR..." >&2
  exit 2
fi
hdr4d="$(realpath "$1")"
work="$2"
shift 2
method="${METHOD:-hdr-hexplane}" supervision="${SUPERVISION:-ldr+hdr}"
models="${MODELS:-fixed environment}" seeds="${SEEDS:-0 1}" iterations="${ITERATIONS:-300}"
rays="${RAYS:-512}" grid="${GRID:-32768 262144}" threads="${THREADS:-2}"
mkdir -p "$work"
for scene in "$@"; do
  name="$(basename "$scene")"
  for seed in $seeds; do
    for model in $models; do
      out="$work/$name-$model-s$seed"
      if [ ! -f "$out/results.json" ]; then
        /usr/bin/time -f "cpu_user %U cpu_sys %S wall %e" -o "$out.time" "$hdr4d" train \
          --data "$scene" --out "$out" --overwrite --method "$method" --supervision "$supervision" \
          --iterations "$iterations" --rays "$rays" --grid-voxels $grid --threads "$threads" \
          --seed "$seed" --grid-background "$model" > "$out.log" 2>&1 ||
          { echo "$out: failed, see $out.log"; continue; }
      fi
      python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
r = json.load(open(out + "/results.json"))
t = dict(zip(*[iter(open(out + ".time").read().split())] * 2))
cpu = float(t["cpu_user"]) + float(t["cpu_sys"])
test = r["test"]
hdr = {k: round(v, 3) for k, v in test.items()
       if isinstance(v, (int, float)) and k not in ("psnr", "ssim")}
print(f"{out.rsplit('/', 1)[-1]:36s} held-out LDR {test['psnr']:.2f} dB, SSIM {test['ssim']:.3f}; "
      f"{cpu:.0f} CPU-s; {json.dumps(hdr)}")
PY
    done
  done
done
