#!/usr/bin/env bash
# Does the learned per-camera correction (`hdr4d train --camera-correction`,
# method/tonemap/camera_correction.h) help where each camera has its own pipeline? Copies of
# datagen mini scenes are filmed again (`synth-ldr`) through `auto-exposure --ae-scope camera`
# (each camera its own meter and gain) and `rig-mismatch` (each camera its own gain, response
# and colour matrix), and HDR-4DGS (DTM) trains on each with and without the correction under
# LDR supervision, the pipelines suite's settings, through `hdr4d bench`: one ablation table per
# pipeline with the paired test (pairs by scene and seed) against DTM without it, and the
# verdict lines with a chart per pipeline (`bench findings`, into WORK/findings).
#
# Usage: bash benchmark/proofs/camera_correction.sh WORK [SCENES] [SEEDS] [ITERATIONS]
#   WORK        a folder for the scene copies, the suite, the store and the runs
#   SCENES      comma-separated: datagen scenes with several cameras (from MINI), or `demo`:
#               core's demo scene, 6 cameras, 12 timestamps at 96 px, whose test split is made
#               the held-out times 2, 6, 10 of its five training cameras (the sixth camera,
#               held out, is dropped: with no gains of its own it would test the identity)
#               (default demo,hook)
#   SEEDS       default 0,1,2
#   ITERATIONS  default 3000
# Environment: HDR4D (default build/cli/hdr4d), MINI (default /work/data/mini: `hdr4d datagen
# --scene all --preset mini --out MINI), ANY_CODE_VERSION=1 (runs an earlier code version stored
# in WORK's store count as done: `bench run --any-code-version`, to add seeds over sessions; the
# pairs stay within one version, each seed's two rows being run together).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
work="${1:?usage: camera_correction.sh WORK [SCENES] [SEEDS] [ITERATIONS]}"
scenes="${2:-demo,hook}"
seeds="${3:-0,1,2}"
iterations="${4:-3000}"
hdr4d="${HDR4D:-$root/build/cli/hdr4d}"
mini="${MINI:-/work/data/mini}"
mkdir -p "$work/data"
work="$(cd "$work" && pwd)"

# The demo scene with held-out times of its training cameras as the test split.
make_demo() {
  "$hdr4d" make-demo-scene --out "$1" --size 96 --timestamps 12 --cameras 6 >"$1.make.log" 2>&1
  python3 - "$1" <<'EOF'
import json, sys
root = sys.argv[1] + "/"
train = json.load(open(root + "transforms_train.json"))
test = json.load(open(root + "transforms_test.json"))
times = sorted({f["time"] for f in train["frames"]})
held = {times[i] for i in (2, 6, 10)}
test["frames"] = [f for f in train["frames"] if f["time"] in held]
train["frames"] = [f for f in train["frames"] if f["time"] not in held]
json.dump(train, open(root + "transforms_train.json", "w"), indent=1)
json.dump(test, open(root + "transforms_test.json", "w"), indent=1)
EOF
}

# The scene copies, filmed through each pipeline (the copy's HDR, poses and point cloud are the
# scene's; only its LDR images are made again).
declare -A flags=([ae-camera]="--pipeline auto-exposure --ae-scope camera"
                  [rig-mismatch]="--pipeline rig-mismatch")
scene_json=""
for scene in ${scenes//,/ }; do
  for pipeline in ae-camera rig-mismatch; do
    copy="$work/data/$scene-$pipeline"
    if [[ ! -f $copy/DONE ]]; then
      rm -rf "$copy"
      if [[ $scene == demo ]]; then
        make_demo "$copy"
      else
        cp -r "$mini/$scene" "$copy"
      fi
      # shellcheck disable=SC2086
      "$hdr4d" synth-ldr --data "$copy" ${flags[$pipeline]} --overwrite >"$copy.synth.log" 2>&1
      touch "$copy/DONE"
    fi
    scene_json+="${scene_json:+,}{\"name\": \"$scene-$pipeline\", \"group\": \"$pipeline\", \"path\": \"$copy\"}"
  done
done

table() {  # one ablation table of a pipeline's scenes
  cat <<EOF
{"id": "correction-$1", "title": "Learned per-camera correction, $1", "layout": "ablation",
 "scenes": "$1", "reference": "DTM",
 "finding": "DTM without the correction beats DTM with it ('does not hold' where the correction wins)",
 "rows": [{"label": "DTM + camera correction", "method": "dtm-cc", "supervision": "ldr"},
          {"label": "DTM", "method": "dtm", "supervision": "ldr"}],
 "note": "LDR-only supervision; the correction's gains are learned per training camera and used for its held-out times."}
EOF
}
cat >"$work/camera-correction.json" <<EOF
{"name": "camera-correction",
 "description": "HDR-4DGS with and without --camera-correction on mini scenes filmed through per-camera pipelines (benchmark/proofs/camera_correction.sh)",
 "scenes": [$scene_json],
 "methods": [{"name": "dtm", "label": "DTM", "train": {"method": "hdr4dgs"}},
             {"name": "dtm-cc", "label": "DTM + camera correction",
              "train": {"method": "hdr4dgs", "camera-correction": true}}],
 "supervision": ["ldr"],
 "seeds": [${seeds}],
 "budgets": [{"iterations": $iterations}],
 "train": {"no-learn-background": true, "densify-from": {"of_iterations": 0.1667},
           "densify-grad-threshold": 0.001, "densify-until": {"of_iterations": 0.8333},
           "position-lr-steps": {"of_iterations": 1}},
 "tables": [$(table ae-camera), $(table rig-mismatch)]}
EOF
resume=()
[[ ${ANY_CODE_VERSION:-0} == 1 ]] && resume=(--any-code-version)
"$hdr4d" bench run "$work/camera-correction.json" --store "$work/store.sqlite" --jobs 1 "${resume[@]}"
"$hdr4d" bench table "$work/camera-correction.json" --store "$work/store.sqlite" --all-metrics
"$hdr4d" bench table "$work/camera-correction.json" --store "$work/store.sqlite" --per-scene
"$hdr4d" bench findings "$work/camera-correction.json" --store "$work/store.sqlite" \
  --metrics psnr,mu_psnr_aligned,flip --out "$work/findings"
