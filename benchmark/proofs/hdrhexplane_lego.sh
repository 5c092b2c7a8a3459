#!/usr/bin/env bash
# HDR-HexPlane's own dataset/lego, as its first commit holds it, read by hdr4d (issue 56):
#   1. `dataset check` in seconds (the default): refused, with the stops diagnosis and the fix
#   2. `dataset check --exposure-unit stops`: what is read (frames per split, exposures, times)
#      and what is missing (the commit holds 7 of the 240 training images and 8 of the 60 test
#      images; the rest were to be downloaded)
#   3. the frames whose images the commit holds, as a scene of their own: checked, trained
#      (ITERATIONS, --background 1: HDR-HexPlane composites its RGBA images over white) and
#      rendered with --exposure-unit stops, the run recording the unit
# The dataset is not copied into this repository: its README says "All the datasets are
# provided for academic studies only", which the code's MIT licence does not lift. Usage:
#   bash benchmark/proofs/hdrhexplane_lego.sh GIT_DIR BINARY WORKDIR
# GIT_DIR: a clone of github.com/hustvl/HDR-HexPlane (a bare one will do). WORKDIR is replaced.
# Settings from the environment: ITERATIONS [300], RESOLUTION [8] (800 / 8 = 100 pixels),
# THREADS [2]. About a minute on 2 cores at the defaults.
set -euo pipefail
if [ $# -ne 3 ]; then
  echo "usage: $0 GIT_DIR BINARY WORKDIR" >&2
  exit 2
fi
git_dir="$1"
hdr4d="$(realpath "$2")"
work="$3"
[ -x "$hdr4d" ] || { echo "$0: $2: not an executable" >&2; exit 2; }
iterations="${ITERATIONS:-300}" resolution="${RESOLUTION:-8}" threads="${THREADS:-2}"

commit="$(git --git-dir "$git_dir" rev-list --max-parents=0 HEAD | tail -n 1)"
rm -rf "$work"
mkdir -p "$work"
git --git-dir "$git_dir" archive "$commit" dataset/lego | tar -x -C "$work"
scene="$work/dataset/lego"
echo "== HDR-HexPlane first commit $commit ($(git --git-dir "$git_dir" log -1 --format=%ad "$commit"))"
ls "$scene"
echo "images held: train $(ls "$scene/train" | wc -l), test $(ls "$scene/test" | wc -l)"

echo "== 1. dataset check (seconds)"
set +e
"$hdr4d" dataset check "$scene" > "$work/check_seconds.txt" 2> /dev/null
code=$?
set -e
echo "exit $code"
grep -m 3 "exposures" "$work/check_seconds.txt" || true

echo "== 2. dataset check --exposure-unit stops"
set +e
"$hdr4d" dataset check --exposure-unit stops --json "$scene" > "$work/check_stops.json" \
  2> /dev/null
echo "exit $?"
set -e
python3 - "$work/check_stops.json" <<'EOF'
import collections, json, sys
report = json.load(open(sys.argv[1]))
kinds = collections.Counter()
for p in report["problems"]:
    message = p["message"].rsplit(": ", 1)[-1]  # without the image's path
    kinds[(p["file"].rsplit("/", 1)[-1], p.get("key", ""), message)] += 1
print(f"  {len(report['problems'])} problems:")
for (file, key, message), n in sorted(kinds.items()):
    print(f"  {n:4d} x {file}: {key}: {message}")
summary = report.get("summary", {})
for key in ("layout", "frames", "cameras", "exposure_unit", "exposures_written", "exposures",
            "time_raw", "time", "resolution", "hdr_gt"):
    if key in summary:
        print(f"  {key}: {json.dumps(summary[key])}")
EOF

echo "== 3. the frames the commit holds images for, as one scene"
held="$work/lego_held"
python3 - "$scene" "$held" <<'EOF'
import json, os, shutil, sys
src, dst = sys.argv[1], sys.argv[2]
docs = {s: json.load(open(os.path.join(src, f"transforms_{s}.json"))) for s in ("train", "test")}
# The whole scene's largest time (299): written as each kept frame's time over it, the kept
# frames keep the normalised times the whole scene gives them.
largest = max(f["time"] for d in docs.values() for f in d["frames"])
for split, doc in docs.items():
    kept = [f for f in doc["frames"] if os.path.exists(os.path.join(src, f["file_path"]))]
    for f in kept:
        os.makedirs(os.path.dirname(os.path.join(dst, f["file_path"])), exist_ok=True)
        shutil.copy(os.path.join(src, f["file_path"]), os.path.join(dst, f["file_path"]))
    doc["frames"] = [dict(f, time=f["time"] / largest) for f in kept]
    json.dump(doc, open(os.path.join(dst, f"transforms_{split}.json"), "w"), indent=1)
    print(f"  {split}: {len(kept)} frames kept,", "exposures (stops)",
          [f["exposures"] for f in kept], "times", [f["time"] for f in kept])
EOF
"$hdr4d" dataset check --exposure-unit stops "$held" 2> /dev/null | sed 's/^/  /'
run="$work/run"
/usr/bin/time -f "  train: %U s user, %S s sys, %e s wall" \
  "$hdr4d" train --data "$held" --out "$run" --exposure-unit stops --resolution "$resolution" \
  --background 1 --iterations "$iterations" --threads "$threads" --supervision ldr 2>&1 |
  grep -v "^\s*$" | tail -n 4
python3 -c "import json,sys; c=json.load(open(sys.argv[1])); print('  config exposure_unit:', c['exposure_unit'])" \
  "$run/config.json"
"$hdr4d" render --run "$run" --split test | tail -n 1
python3 - "$run/results.json" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
print("  held-out (test) metrics:", {k: round(v, 3) for k, v in r["test"].items()
                                     if k in ("psnr", "ssim") and isinstance(v, float)})
EOF
ls "$run/renders/test" | head -n 3
