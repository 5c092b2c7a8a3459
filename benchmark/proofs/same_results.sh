#!/usr/bin/env bash
# Two hdr4d binaries (before and after a refactor) give bit-identical results: the same seeded
# training runs and renders with both, then the checkpoints, the renders and results.json
# compared by SHA-256, all without their wall-clock fields and the measured peak memory.
#   bash benchmark/proofs/same_results.sh OLD_HDR4D NEW_HDR4D WORKDIR [ITERATIONS]
# SAME_RESULTS_IGNORE=flip,hdr_flip leaves out results.json keys that one side adds by design
# (metrics new since OLD); checkpoints and renders are always compared whole.
# SAME_RESULTS_NEW_FLAGS="--reference" adds train flags to NEW's runs only (a configuration
# OLD trains by default under a name it does not know; issue 55).
# Runs: HDR-4DGS and HDR-GS on the built-in demo scene (LDR supervision, 8 cameras), and 4DGS
# on ../shared/data/dnerf_lego_tiny when it is there. Exit status 1 when anything differs.
set -euo pipefail
OLD=$(realpath "$1"); NEW=$(realpath "$2"); WORK=$3; ITERS=${4:-600}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
LEGO="$ROOT/../shared/data/dnerf_lego_tiny"
mkdir -p "$WORK"
status=0

# results.json without the wall-clock fields, as canonical JSON.
strip_times() {
  python3 -c 'import json,os,sys
ignore = {"fps", "peak_rss_mb"} | set(filter(None, os.environ.get("SAME_RESULTS_IGNORE", "").split(",")))
def drop(x):
    if isinstance(x, dict):
        return {k: drop(v) for k, v in x.items() if "seconds" not in k and k not in ignore}
    if isinstance(x, list):
        return [drop(v) for v in x]
    return x
print(json.dumps(drop(json.load(open(sys.argv[1]))), sort_keys=True))' "$1" | sha256sum | cut -c1-16
}

# A checkpoint without its wall-clock field: magic, header JSON (trainer.train_seconds dropped),
# then every byte of the model, statistics, Adam and tone-mapper state (the trailer's checksum
# covers the time too, so it is left out).
checkpoint_hash() {
  python3 -c 'import hashlib,json,struct,sys
b=open(sys.argv[1],"rb").read()
n=struct.unpack("<Q",b[8:16])[0]
h=json.loads(b[16:16+n]); h["trainer"].pop("train_seconds",None)
m=hashlib.sha256(); m.update(b[:8]); m.update(json.dumps(h,sort_keys=True).encode()); m.update(b[16+n:-16])
print(m.hexdigest()[:16])' "$1"
}

# Files under a folder, each with its hash (images and checkpoints).
tree_hash() { (cd "$1" && find . -type f ! -name '*.json' ! -name '.hdr4d-lock' | sort | xargs sha256sum) | sha256sum | cut -c1-16; }

run_pair() {  # name, data, then train flags
  local name=$1 data=$2; shift 2
  for side in old new; do
    local bin=$OLD extra=(); [ "$side" = new ] && bin=$NEW
    # shellcheck disable=SC2206
    [ "$side" = new ] && extra=(${SAME_RESULTS_NEW_FLAGS:-})
    rm -rf "$WORK/$name-$side"
    "$bin" train --data "$data" --out "$WORK/$name-$side/run" --seed 0 --iterations "$ITERS" \
      "$@" "${extra[@]}" > "$WORK/$name-$side.log" 2>&1
    "$bin" render --run "$WORK/$name-$side/run" --out "$WORK/$name-$side/renders" \
      >> "$WORK/$name-$side.log" 2>&1
  done
  local c_old c_new r_old r_new j_old j_new
  c_old=$(checkpoint_hash "$WORK/$name-old/run/checkpoint.bin")
  c_new=$(checkpoint_hash "$WORK/$name-new/run/checkpoint.bin")
  r_old=$(tree_hash "$WORK/$name-old/renders"); r_new=$(tree_hash "$WORK/$name-new/renders")
  j_old=$(strip_times "$WORK/$name-old/run/results.json")
  j_new=$(strip_times "$WORK/$name-new/run/results.json")
  printf '%-14s checkpoint %s %s | renders %s %s | results %s %s\n' "$name" \
    "$c_old" "$c_new" "$r_old" "$r_new" "$j_old" "$j_new"
  if [ "$c_old" != "$c_new" ] || [ "$r_old" != "$r_new" ] || [ "$j_old" != "$j_new" ]; then
    echo "  DIFFERENT: see $WORK/$name-old and $WORK/$name-new"; status=1
  fi
}

# The demo scene, made by each binary and compared too.
for side in old new; do
  bin=$OLD; [ "$side" = new ] && bin=$NEW
  rm -rf "$WORK/scene-$side"
  "$bin" make-demo-scene --out "$WORK/scene-$side" --cameras 8 > /dev/null 2>&1
  "$bin" synth-ldr --data "$WORK/scene-$side" > /dev/null 2>&1
done
s_old=$(tree_hash "$WORK/scene-old"); s_new=$(tree_hash "$WORK/scene-new")
printf '%-14s files %s %s\n' "demo scene" "$s_old" "$s_new"
[ "$s_old" = "$s_new" ] || { echo "  DIFFERENT demo scenes"; status=1; }

run_pair hdr4dgs-demo "$WORK/scene-old"
# A baseline: the static MLP tone mapper (registered by baselines/) without the time axis, so
# the 3D preprocess path runs.
run_pair hdr-gs-demo "$WORK/scene-old" --method hdr-gs
if [ -d "$LEGO" ]; then
  run_pair 4dgs-lego "$LEGO" --method 4dgs
else
  echo "4dgs-lego      skipped: $LEGO not found"
fi
exit $status
