#!/usr/bin/env bash
# The main job end to end on the built-in default scene: install, build, render a small dynamic
# HDR scene, synthesise its multi-exposure LDR images, validate the dataset, merge the exposure
# brackets back to HDR and score them against the ground truth. Output: demo/ (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-demo}
bash scripts/install-deps.sh
bash scripts/build.sh
HDR4D=${HDR4D_BUILD_DIR:-build}/cli/hdr4d

rm -rf "$OUT"
echo "== 1. render the built-in dynamic HDR scene (4 cameras x 6 timestamps, 96x96)"
"$HDR4D" make-demo-scene --out "$OUT/scene"
echo "== 2. synthesise LDR at 0.125 s, 2 s and 32 s (filmic response, shot + read noise, 8 bit)"
"$HDR4D" synth-ldr --data "$OUT/scene" --crf filmic --full-well 20000 --read-noise 0.002 --seed 1
echo "== 3. validate the dataset and draw a contact sheet of the test camera"
"$HDR4D" dataset check "$OUT/scene" --full
"$HDR4D" dataset preview "$OUT/scene" --out "$OUT/preview.png"
echo "== 4. merge each test view's exposure bracket back to HDR"
"$HDR4D" merge-hdr --data "$OUT/scene" --out "$OUT/merged" --split test
echo "== 5. score the merged HDR against the ground truth"
"$HDR4D" eval "$OUT/merged" "$OUT/scene/hdr" --out "$OUT/eval.json"
echo "demo: done; the dataset is in $OUT/scene, a picture of it in $OUT/preview.png, the scores in $OUT/eval.json"
