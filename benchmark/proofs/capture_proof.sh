#!/usr/bin/env bash
# The end-to-end proof of `hdr4d calibrate` on a synthetic rig with known truth (issue 14):
#   1. `hdr4d datagen --capture`: the room scene filmed by a fixed rig (CAMERAS cameras 30 degrees
#      apart, the last held out, FRAMES frames of BRACKETS, static images of the empty room and
#      EXTRA hand-held views of it), with the truth beside it (poses, intrinsics, response,
#      rendered EXRs, the original dataset)
#   2. `hdr4d calibrate --truth`: COLMAP + Ceres, Debevec-Malik, fusion, gains; compared with the
#      truth (rotation and position after a similarity, focal length, response, fused HDR)
#   3. `hdr4d train` (ITERATIONS, LDR supervision) on the calibrated dataset and on the original
#      one, both scored on the held-out camera
# and prints one table. Usage:
#   bash benchmark/proofs/capture_proof.sh BINARY WORKDIR
# Settings from the environment (defaults in square brackets): CAMERAS [6], FRAMES [4], WIDTH [320],
# EXTRA [6] hand-held views, BRACKETS [0.5,2,8] seconds, SAMPLES [32], UNLIKE [none]
# (none|gains|responses|both), ITERATIONS [2000], SEED [0], THREADS [0 = every core].
# With alike cameras the held-out camera's brackets are byte for byte the original dataset's
# test images, so the two trainings are scored against the same images; with unlike cameras
# the calibrated run is scored against what the held-out camera recorded (its own colour).
# WORKDIR is replaced. About 6 minutes on 2 cores at the defaults.
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 BINARY WORKDIR" >&2
  exit 2
fi
hdr4d="$(realpath "$1")"
work="$2"
[ -x "$hdr4d" ] || { echo "$0: $1: not an executable" >&2; exit 2; }
cameras="${CAMERAS:-6}" frames="${FRAMES:-4}" width="${WIDTH:-320}" samples="${SAMPLES:-32}"
extra="${EXTRA:-6}" brackets="${BRACKETS:-0.5,2,8}"
unlike="${UNLIKE:-none}" iterations="${ITERATIONS:-2000}" seed="${SEED:-0}" threads="${THREADS:-0}"
rm -rf "$work" && mkdir -p "$work"
work="$(realpath "$work")"
times="$work/stage_times.txt"
: > "$times"

# stage NAME COMMAND...: runs it with its output in WORKDIR/NAME.log, records its wall time.
stage() {
  local name="$1"
  shift
  local start end
  start=$(date +%s.%N)
  if ! "$@" > "$work/$name.log" 2>&1; then
    echo "$0: stage $name failed; its log ($work/$name.log) ends:" >&2
    tail -5 "$work/$name.log" >&2
    exit 1
  fi
  end=$(date +%s.%N)
  echo "$name $(echo "$end - $start" | bc)" >> "$times"
  echo "capture proof: $name done in $(echo "$end - $start" | bc | xargs printf '%.1f') s" >&2
}

capture="$work/capture/room"
stage datagen "$hdr4d" datagen --capture --scene room --preset mini --width "$width" \
  --samples "$samples" --cameras "$cameras" --frames "$frames" --extra-views "$extra" \
  --brackets "$brackets" --unlike-cameras "$unlike" \
  --seed "$seed" --threads "$threads" --out "$work/capture"
stage calibrate "$hdr4d" calibrate --capture "$capture" --out "$work/calibrated" \
  --truth "$capture/truth"
# The same schedule on both: densification from 300 to 80% of the run, no opacity reset (a reset
# late in a short run costs several dB, issue 12), LDR supervision (the HDR is only scored).
train() {
  "$hdr4d" train --data "$1" --out "$2" --iterations "$iterations" --supervision ldr \
    --seed "$seed" --threads "$threads" --densify-from 300 \
    --densify-until $((iterations * 4 / 5)) --position-lr-steps "$iterations" \
    --opacity-reset-interval "$iterations"
}
stage train_original train "$capture/truth" "$work/train_original"
stage train_calibrated train "$work/calibrated" "$work/train_calibrated"

python3 - "$work" "$capture" "$cameras" "$frames" "$width" "$unlike" "$iterations" "$extra" "$brackets" <<'EOF'
import json, sys
work, capture, cameras, frames, width, unlike, iterations, extra, brackets = sys.argv[1:]
times = dict(line.split() for line in open(f"{work}/stage_times.txt"))
c = json.load(open(f"{work}/calibrated/truth_comparison.json"))
calibration = json.load(open(f"{work}/calibrated/calibration.json"))
manifest = json.load(open(f"{capture}/manifest.json"))
runs = {name: json.load(open(f"{work}/train_{name}/results.json"))
        for name in ("original", "calibrated")}
h = manifest["render"]["height"]
print(f"\n## Capture proof: room, {cameras} cameras ({width}x{h}) + {extra} hand-held views, "
      f"{frames} frames x brackets {brackets} s, unlike cameras: {unlike}\n")
print("| stage | wall time (s) |\n|---|---|")
print(f"| datagen --capture (Blender {manifest['timing']['blender_seconds']:.1f} s for "
      f"{len([1 for _ in manifest['files']])} files) | {float(times['datagen']):.1f} |")
print(f"| calibrate (geometry {calibration['seconds']['geometry']:.1f} s, radiometry "
      f"{calibration['seconds']['radiometry']:.1f} s) | {float(times['calibrate']):.1f} |")
print(f"| train on the original dataset ({iterations} iterations) | {float(times['train_original']):.1f} |")
print(f"| train on the calibrated dataset ({iterations} iterations) | {float(times['train_calibrated']):.1f} |")
print("\n| calibration against the truth | value |\n|---|---|")
g = c.get("geometry")
if g:
    print(f"| rotation error after a similarity, max / mean (deg) | {g['max_rotation_error_deg']:.3f} / {g['mean_rotation_error_deg']:.3f} |")
    print(f"| position error, max / mean (% of the rig size, {g['rig_size']:.2f} units) | "
          f"{100 * g['max_position_error_relative']:.2f} / {100 * g['mean_position_error_relative']:.2f} |")
    print(f"| focal length error, max | {100 * g['max_focal_error_relative']:.2f}% |")
r = c.get("response")
if r:
    print(f"| response (codes 16-240) max / RMS relative error, r g b | "
          + " ".join(f"{100 * v:.1f}%" for v in r["max_relative_error"]) + " / "
          + " ".join(f"{100 * v:.1f}%" for v in r["rms_relative_error"]) + " |")
d = c.get("hdr")
if d:
    print(f"| fused HDR vs rendered EXR: median / p90 relative error | {100 * d['median_relative_error']:.1f}% / {100 * d['p90_relative_error']:.1f}% |")
    print(f"| fused HDR values within 10% | {100 * d['within_10_percent']:.1f}% ({100 * d['excluded_pixel_fraction']:.1f}% of pixels outside the bracketed range) |")
gains = calibration.get("camera_agreement")
if gains:
    print(f"| cameras' disagreement on shared points, before / after the gains | "
          f"{100 * gains.get('disagreement_before', 0):.1f}% / {100 * gains.get('disagreement_after', 0):.1f}% |")
for note in c.get("notes", []):
    print(f"| note | {note} |")

def metric(run, key):
    for section in ("test_metrics", "test", "metrics"):
        if isinstance(run.get(section), dict) and key in run[section]:
            return run[section][key]
    return run.get(key)

# HDR against each dataset's own HDR (rendered EXRs; fused brackets), after one scale: the runs
# learn radiance from LDR images only, up to scale.
keys = [("psnr", "LDR PSNR (dB)"), ("ssim", "LDR SSIM"),
        ("mu_psnr_aligned", "HDR mu-PSNR, scale-aligned (dB)")]
print("\n| held-out camera | " + " | ".join(label for _, label in keys) + " |")
print("|---|" + "---|" * len(keys))
for name in ("original", "calibrated"):
    cells = []
    for key, _ in keys:
        v = metric(runs[name], key)
        cells.append("-" if v is None else f"{v:.3f}" if "ssim" in key else f"{v:.2f}")
    print(f"| {name} dataset | " + " | ".join(cells) + " |")
cells = []
for key, _ in keys:
    a, b = metric(runs["calibrated"], key), metric(runs["original"], key)
    cells.append("-" if a is None or b is None else f"{a - b:+.3f}" if "ssim" in key else f"{a - b:+.2f}")
print("| calibrated - original | " + " | ".join(cells) + " |")
EOF
