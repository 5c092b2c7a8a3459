#!/usr/bin/env bash
# `hdr4d calibrate` over a grid of synthetic capture variants and seeds (issue 54): for each
# WIDTH:EXTRA:UNLIKE variant and each seed, `datagen --capture` (room, mini preset) then
# `calibrate --truth`, and one table row of errors against the truth. Usage:
#   bash benchmark/proofs/calibration_grid.sh BINARY WORKDIR
# Settings from the environment (defaults in square brackets): VARIANTS ["320:0:none
# 640:6:gains 640:12:responses 1280:3:both"] (width in pixels, 4:3 images; hand-held extra
# views; unlike cameras none|gains|responses|both), SEEDS ["0"], CAMERAS [4], FRAMES [2],
# BRACKETS [0.5,2,8], SAMPLES [16], THREADS [0 = every core]. WORKDIR is replaced; a variant
# that fails is a row saying where, the grid goes on.
set -uo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 BINARY WORKDIR" >&2
  exit 2
fi
hdr4d="$(realpath "$1")"
work="$2"
variants="${VARIANTS:-320:0:none 640:6:gains 640:12:responses 1280:3:both}"
seeds="${SEEDS:-0}" cameras="${CAMERAS:-4}" frames="${FRAMES:-2}" brackets="${BRACKETS:-0.5,2,8}"
samples="${SAMPLES:-16}" threads="${THREADS:-0}"
rm -rf "$work" && mkdir -p "$work"
work="$(realpath "$work")"
echo "| width | extra views | unlike | seed | registered (rung) | rotation max (deg) | centre max (% rig) | focal max | distortion kept | HDR median error | disagreement after gains | calibrate (s) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for variant in $variants; do
  IFS=: read -r width extra unlike <<< "$variant"
  for seed in $seeds; do
    dir="$work/w${width}_e${extra}_${unlike}_s${seed}"
    mkdir -p "$dir"
    if ! "$hdr4d" datagen --capture --scene room --preset mini --width "$width" --samples "$samples" \
        --cameras "$cameras" --frames "$frames" --extra-views "$extra" --brackets "$brackets" \
        --unlike-cameras "$unlike" --seed "$seed" --threads "$threads" --out "$dir/capture" \
        > "$dir/datagen.log" 2>&1; then
      echo "| $width | $extra | $unlike | $seed | datagen failed: $(tail -1 "$dir/datagen.log") |||||||||"
      continue
    fi
    start=$(date +%s.%N)
    if ! "$hdr4d" calibrate --capture "$dir/capture/room" --out "$dir/calibrated" \
        --truth "$dir/capture/room/truth" > "$dir/calibrate.log" 2>&1; then
      echo "| $width | $extra | $unlike | $seed | calibrate failed: $(tail -1 "$dir/calibrate.log") |||||||||"
      continue
    fi
    seconds=$(echo "$(date +%s.%N) - $start" | bc)
    python3 - "$dir" "$width" "$extra" "$unlike" "$seed" "$seconds" <<'PY'
import json, re, sys
d, width, extra, unlike, seed, seconds = sys.argv[1:]
c = json.load(open(f"{d}/calibrated/truth_comparison.json"))
cal = json.load(open(f"{d}/calibrated/calibration.json"))
report = open(f"{d}/calibrated/report.md").read()
rung = re.search(r"rung (\d) of the registration ladder \(([^;]*);", report)
g, h = c.get("geometry", {}), c.get("hdr", {})
kept = sum(1 for cam in cal.get("cameras", []) if cam.get("distortion_kept"))
gains = cal.get("camera_agreement", {})
print(f"| {width} | {extra} | {unlike} | {seed} | {'rung ' + rung.group(1) + ' (' + rung.group(2) + ')' if rung else '?'} | "
      f"{g.get('max_rotation_error_deg', float('nan')):.3f} | {100 * g.get('max_position_error_relative', float('nan')):.2f} | "
      f"{100 * g.get('max_focal_error_relative', float('nan')):.2f}% | {kept} of {len(cal.get('cameras', []))} | "
      f"{100 * h.get('median_relative_error', float('nan')):.1f}% | {100 * gains.get('disagreement_after', float('nan')):.1f}% | "
      f"{float(seconds):.0f} |")
PY
  done
done
