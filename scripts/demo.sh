#!/usr/bin/env bash
# The main job end to end on built-in default scenes: install, build, render a small dynamic HDR
# scene, synthesise its multi-exposure LDR images, validate the dataset, merge the exposure
# brackets back to HDR and score them; train HDR-4DGS on the LDR images alone and score its HDR
# and LDR renders and plot its tone curves; then train 4D Gaussian Splatting on a known moving
# Gaussian scene, render its held-out cameras and score them. Output: demo/ (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-demo}
bash scripts/install-deps.sh
HDR4D_TARGET=hdr4d bash scripts/build.sh  # only the binary: the tests are scripts/test.sh's
HDR4D=${HDR4D_BUILD_DIR:-build}/cli/hdr4d

rm -rf "$OUT"
echo "== 1. render the built-in dynamic HDR scene (8 cameras x 6 timestamps, 96x96)"
"$HDR4D" make-demo-scene --out "$OUT/scene" --cameras 8
echo "== 2. synthesise LDR at 0.125 s, 2 s and 32 s (filmic response, shot + read noise, 8 bit)"
"$HDR4D" synth-ldr --data "$OUT/scene" --crf filmic --full-well 20000 --read-noise 0.002 --seed 1
echo "== 3. validate the dataset and draw a contact sheet of the test camera"
"$HDR4D" dataset check "$OUT/scene" --full
"$HDR4D" dataset preview "$OUT/scene" --out "$OUT/preview.png"
echo "== 4. merge each test view's exposure bracket back to HDR"
"$HDR4D" merge-hdr --data "$OUT/scene" --out "$OUT/merged" --split test
echo "== 5. score the merged HDR against the ground truth"
"$HDR4D" eval "$OUT/merged" "$OUT/scene/hdr" --out "$OUT/eval.json"
echo "== 6. train HDR-4DGS (Dynamic Tone Mapper) from the LDR brackets alone, no HDR supervision"
# Default schedules: they follow --iterations (docs/history/accuracy.md, issue 12 §1).
"$HDR4D" train --data "$OUT/scene" --out "$OUT/hdr_run" --supervision ldr --iterations 3000
echo "== 7. render its held-out camera (LDR PNG + HDR EXR), score both, plot the learned tone curves"
"$HDR4D" render --run "$OUT/hdr_run" --split test
"$HDR4D" eval "$OUT/hdr_run/renders/test" "$OUT/scene/images" --out "$OUT/hdr_run/eval_ldr.json"
"$HDR4D" eval "$OUT/hdr_run/renders/test" "$OUT/scene/hdr" --out "$OUT/hdr_run/eval_hdr.json"
"$HDR4D" tone-curves --run "$OUT/hdr_run"
echo "== 8. train 4D Gaussian Splatting on a known moving Gaussian scene (96x96, 12 cameras x 8 times)"
"$HDR4D" make-gaussian-scene --out "$OUT/gaussians" --size 96
"$HDR4D" train --data "$OUT/gaussians" --out "$OUT/run" --method 4dgs --iterations 3000 --random-points 5000 \
  --densify-until 2000 --position-lr-steps 3000 --densify-grad-threshold 1e-3
echo "== 9. render the held-out cameras, score them, export a time slice for any 3DGS viewer"
"$HDR4D" render --run "$OUT/run" --split test
"$HDR4D" eval "$OUT/run/renders/test" "$OUT/gaussians/images" --out "$OUT/run/eval.json"
"$HDR4D" export-ply --run "$OUT/run" --time 0.5
echo "demo: done; HDR dataset in $OUT/scene (picture: $OUT/preview.png, merge scores: $OUT/eval.json);"
echo "      HDR-4DGS run in $OUT/hdr_run (results.json, renders/test, tone_curves/tone_curves.png);"
echo "      trained run in $OUT/run (results.json, renders/test, slice_t0.500.ply)"
