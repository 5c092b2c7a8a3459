#!/usr/bin/env bash
# `hdr4d calibrate` over a grid of synthetic capture variants and seeds (issue 54): for each
# variant and each seed, `datagen --capture` (room, mini preset) then `calibrate --truth`, and
# one table row of errors against the truth. Usage:
#   bash benchmark/proofs/calibration_grid.sh BINARY WORKDIR
# A variant is SIZE:EXTRA:UNLIKE[:LENSES[:BRACKETS[:BLACK]]]: SIZE WxH (or a width, 4:3);
# EXTRA hand-held views; UNLIKE none|gains|responses|both; LENSES none|distortion|vignetting|both
# [none]; BRACKETS a comma list of seconds or dN for --dense-brackets N [$BRACKETS]; BLACK
# --black-level's B[:SIGMA] [none]. Settings from the environment (defaults in square brackets):
# VARIANTS ["320x240:0:none 640x480:6:gains 640x480:12:responses:distortion 1280x720:3:both"],
# SEEDS ["0"], CAMERAS [4], FRAMES [2], BRACKETS [0.5,2,8], SAMPLES [16], THREADS [0 = every core],
# KEEP [0: 1 keeps each capture], REUSE [0: 1 keeps WORKDIR and reuses each variant's capture and
# the COLMAP model of its last calibration, so that calibrate alone reruns], CALIBRATE_FLAGS [more
# flags of calibrate, e.g. --shared-intrinsics or --no-refinement]. Without REUSE WORKDIR is replaced; a variant that fails is a row saying where,
# the grid goes on. Columns: every static view registered (the rig's cameras must be, or
# calibrate fails; hand-held views counted), rotation / centre / focal errors (max over
# cameras), distortion kept, fused HDR log-log slope and median error against the render, and
# the cameras' disagreement after gains three ways: the recovered gains against the true ones
# (max over cameras and channels of their ratio over its geometric mean, 0 where the truth has
# no gains), the spread of each camera's median calibrated/true radiance (truth_comparison's
# camera_disagreement: response errors weighted by what each camera sees count too), and
# calibrate's own on the shared sparse points (their texture's scatter counts too).
set -uo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 BINARY WORKDIR" >&2
  exit 2
fi
hdr4d="$(realpath "$1")"
work="$2"
variants="${VARIANTS:-320x240:0:none 640x480:6:gains 640x480:12:responses:distortion 1280x720:3:both}"
seeds="${SEEDS:-0}" cameras="${CAMERAS:-4}" frames="${FRAMES:-2}" brackets="${BRACKETS:-0.5,2,8}"
samples="${SAMPLES:-16}" threads="${THREADS:-0}" keep="${KEEP:-0}" reuse="${REUSE:-0}"
read -r -a calibrate_flags <<< "${CALIBRATE_FLAGS:-}"
[ "$reuse" = 1 ] || rm -rf "$work"
mkdir -p "$work"
work="$(realpath "$work")"
echo "| size | extra views | unlike | lenses | brackets | seed | registered (rung) | rotation max (deg): centres' similarity / orientations' rotation / camera pairs | centre max (% rig) | focal max | distortion kept | HDR slope | HDR median error (darkest fifth) | gains vs truth | cameras' HDR scales vs truth | sparse-point disagreement before / after gains | calibrate (s) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for variant in $variants; do
  IFS=: read -r size extra unlike lenses bracket_spec black black_sigma <<< "$variant"
  lenses="${lenses:-none}" bracket_spec="${bracket_spec:-$brackets}"
  case "$size" in *x*) size_flag=(--size "$size") ;; *) size_flag=(--width "$size") ;; esac
  case "$bracket_spec" in d*) bracket_flag=(--dense-brackets "${bracket_spec#d}") ;; *) bracket_flag=(--brackets "$bracket_spec") ;; esac
  black_flag=()
  [ -n "${black:-}" ] && black_flag=(--black-level "$black${black_sigma:+:$black_sigma}")
  for seed in $seeds; do
    dir="$work/${size}_e${extra}_${unlike}_${lenses}_${bracket_spec//,/-}_s${seed}"
    mkdir -p "$dir"
    label="| $size | $extra | $unlike | $lenses | $bracket_spec${black:+, black $black${black_sigma:+:$black_sigma}} | $seed"
    model_flag=()
    if [ "$reuse" = 1 ] && [ -d "$dir/calibrated/colmap" ]; then
      rm -rf "$dir/colmap" && mv "$dir/calibrated/colmap" "$dir/colmap"
    fi
    # The ladder stops at the first rung that registers everything: the last rung's model (when
    # no rung did, calibrate took the one that registered most; this may then differ).
    if [ "$reuse" = 1 ] && [ -d "$dir/colmap" ]; then
      model="$(find "$dir/colmap" -name cameras.bin | sort | tail -1)"
      [ -n "$model" ] && model_flag=(--colmap-model "$(dirname "$model")")
    fi
    if [ "$reuse" = 1 ] && [ -f "$dir/capture/room/truth/cameras.json" ]; then
      :
    elif ! nice "$hdr4d" datagen --capture --scene room --preset mini "${size_flag[@]}" --samples "$samples" \
        --cameras "$cameras" --frames "$frames" --extra-views "$extra" "${bracket_flag[@]}" "${black_flag[@]}" \
        --unlike-cameras "$unlike" --lenses "$lenses" --seed "$seed" --threads "$threads" \
        --out "$dir/capture" > "$dir/datagen.log" 2>&1; then
      echo "$label | datagen failed: $(tail -1 "$dir/datagen.log") ||||||||||"
      continue
    fi
    start=$(date +%s.%N)
    rm -rf "$dir/calibrated"
    if ! nice "$hdr4d" calibrate --capture "$dir/capture/room" --out "$dir/calibrated" "${model_flag[@]}" \
        "${calibrate_flags[@]}" --truth "$dir/capture/room/truth" > "$dir/calibrate.log" 2>&1; then
      echo "$label | calibrate failed: $(tail -1 "$dir/calibrate.log") ||||||||||"
      continue
    fi
    seconds=$(echo "$(date +%s.%N) - $start" | bc)
    python3 - "$dir" "$label" "$extra" "$seconds" <<'PY'
import json, re, sys
d, label, extra, seconds = sys.argv[1:]
c = json.load(open(f"{d}/calibrated/truth_comparison.json"))
cal = json.load(open(f"{d}/calibrated/calibration.json"))
report = open(f"{d}/calibrated/report.md").read()
rung = re.search(r"rung (\d) of the registration ladder \(([^;]*);", report)
helped = re.search(r"(\d+) extra image\(s\) helped", report)
g, h = c.get("geometry", {}), c.get("hdr", {})
nan = float("nan")
kept = ", ".join({0: "-", 1: "k1", 2: "k1k2"}[cam.get("distortion_terms", 2) if cam.get("distortion_kept") else 0]
                 for cam in cal.get("cameras", []))
gains = cal.get("camera_agreement", {})
# The gains against the true ones: each camera's recovered / true gain per channel, over the
# cameras' geometric mean (a calibration knows gains only up to one scale per channel).
import math
truth = json.load(open(f"{d}/capture/room/truth/cameras.json"))
true_gain = {t["name"]: t["gain"] for t in truth["cameras"]}
names = [cam["name"] for cam in json.load(open(f"{d}/calibrated/rig.json")).get("cameras", [])]
gain_error = nan
if gains.get("gains") and len(names) == len(gains["gains"]):
    gain_error = 0
    for ch in range(3):
        r = [gains["gains"][i][ch] / true_gain[n][ch] for i, n in enumerate(names)]
        mean = math.exp(sum(math.log(x) for x in r) / len(r))
        gain_error = max(gain_error, max(abs(x / mean - 1) for x in r))
views = f"cameras all, extra {helped.group(1) if helped else '?'}/{extra}"
print(f"{label} | {views}, {'rung ' + rung.group(1) if rung else 'rung ?'} | "
      f"{g.get('max_rotation_error_deg', nan):.3f} / {g.get('max_rotation_error_oriented_deg', nan):.3f} / "
      f"{g.get('max_relative_rotation_error_deg', nan):.3f} | {100 * g.get('max_position_error_relative', nan):.2f} | "
      f"{100 * g.get('max_focal_error_relative', nan):.2f}% | {kept} | "
      f"{h.get('loglog_slope', nan):.3f} | {100 * h.get('median_relative_error', nan):.1f}% ({100 * h.get('dark_fifth_median_relative_error', nan):.1f}%) | "
      f"{100 * gain_error:.1f}% | {100 * h.get('camera_disagreement', nan):.1f}% | "
      f"{100 * gains.get('disagreement_before', nan):.1f}% / {100 * gains.get('disagreement_after', nan):.1f}% | "
      f"{float(seconds):.0f} |")
PY
    [ "$keep" = 1 ] || rm -rf "$dir/capture/room/sequence" "$dir/calibrated/images"
  done
done
