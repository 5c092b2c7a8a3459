#!/usr/bin/env bash
# The grid family's proof (issue 53), at a stated budget, resumable: every finished run is kept
# and skipped when the script is started again, so a later session continues where one stopped.
#   1. dnerf: the real D-NeRF lego (SHARED/data/dnerf_lego_tiny, 100 px): HexPlane and our 4DGS
#      (`train` without --method: 4dgs on a one-exposure LDR scene), DNERF_ITERATIONS each; test
#      PSNR/SSIM from each run's results.json, CPU time from /usr/bin/time.
#   2. mini: every Table 1 row of the `paper` suite (HexPlane: LDR, and HDR = HexPlane*;
#      HDR-HexPlane: LDR, LDR+HDR; 4DGS, 4DGS-HDR, HDR-4DGS: LDR, LDR+HDR and the HDR head;
#      HDR-GS: LDR, LDR+HDR) on the datagen `mini` scenes, seed 0, ITERATIONS each (the suite's
#      1024 rays and reduced grid for the grid methods), into WORKDIR/paper.sqlite (`bench run`
#      skips what the store has: resume by running this again), then Table 1 of that store.
#   3. sides: a side-by-side PNG per scene: truth | HexPlane | HDR-HexPlane LDR | HDR-HexPlane
#      LDR+HDR | 4DGS, first held-out view (ffmpeg's hstack; python3 reads the JSON).
# Usage: bash benchmark/proofs/hexplane_proof.sh BINARY WORKDIR
# Settings from the environment: PARTS ["dnerf mini sides"], ITERATIONS [300], DNERF_ITERATIONS
# [500], RAYS and GRID (D-NeRF HexPlane: rays, voxels at start and end) [1024, "32768 262144",
# as the suite's grid rows; the reference's: 4096, "262144 8000000"], THREADS [2], SCENES [the
# eight], METHODS (the paper suite's methods of part 2) [every Table 1 row's], MINI (the generated
# scenes) [/work/data/mini], SHARED [/work/shared].
# A Gaussian run's config.json names its method under "hdr" (a grid run's at the top).
# WORKDIR/cache/datagen/mini-s0/<scene> link to MINI's scenes, so `bench run` finds them
# generated (nothing is written into MINI).
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 BINARY WORKDIR" >&2
  exit 2
fi
hdr4d="$(realpath "$1")"
work="$2"
[ -x "$hdr4d" ] || { echo "$0: $1: not an executable" >&2; exit 2; }
parts="${PARTS:-dnerf mini sides}"
iterations="${ITERATIONS:-300}" dnerf_iterations="${DNERF_ITERATIONS:-500}"
rays="${RAYS:-1024}" grid="${GRID:-32768 262144}" threads="${THREADS:-2}"
scenes="${SCENES:-airplane deer hook jump lego mutant standup tank}"
methods="${METHODS:-HexPlane HDR-HexPlane 4dgs 4dgs-hdr hdr4dgs hdr4dgs-head hdr-gs}"
mini="${MINI:-/work/data/mini}" shared="${SHARED:-/work/shared}"
mkdir -p "$work"
work="$(realpath "$work")"

timed() {  # LOG COMMAND...: run, appending user/sys/wall seconds to LOG
  local log="$1"
  shift
  /usr/bin/time -f "cpu_user %U cpu_sys %S wall %e" -a -o "$log" "$@"
}

# One training run of the D-NeRF part; skipped when its results.json exists.
dnerf_run() {  # NAME ARGS...
  local name="$1"
  shift
  local out="$work/dnerf/$name"
  if [ -f "$out/results.json" ]; then
    echo "  $name: done before, skipped"
    return
  fi
  mkdir -p "$work/dnerf"
  rm -f "$work/dnerf/$name.time"
  timed "$work/dnerf/$name.time" "$hdr4d" train --data "$shared/data/dnerf_lego_tiny" \
    --out "$out" --overwrite --iterations "$dnerf_iterations" --threads "$threads" "$@" \
    > "$work/dnerf/$name.log" 2>&1
  "$hdr4d" render --run "$out" --split test --out "$out/renders/test" > /dev/null 2>&1
}

if [[ " $parts " == *" dnerf "* ]]; then
  echo "== 1. D-NeRF lego (100 px): $dnerf_iterations iterations, $threads threads"
  dnerf_run hexplane --method hexplane --rays "$rays" --grid-voxels $grid
  dnerf_run 4dgs
  for name in hexplane 4dgs; do
    python3 - "$work/dnerf/$name" "$work/dnerf/$name.time" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1] + "/results.json"))
t = dict(zip(*[iter(open(sys.argv[2]).read().split())] * 2))
cpu = float(t["cpu_user"]) + float(t["cpu_sys"])
it = r.get("iterations", 0)
print(f"  {sys.argv[1].rsplit('/', 1)[-1]:9s} test PSNR {r['test']['psnr']:.2f} dB, SSIM "
      f"{r['test']['ssim']:.3f}; {it} iterations, {cpu:.0f} CPU-s ({cpu / max(it, 1):.3f} per "
      f"iteration), wall {float(t['wall']):.0f} s")
EOF
  done
fi

if [[ " $parts " == *" mini "* ]]; then
  echo "== 2. datagen mini ($scenes): Table 1's rows of the paper suite, $iterations iterations"
  mkdir -p "$work/cache/datagen/mini-s0"
  for s in $scenes; do
    [ -f "$mini/$s/transforms_train.json" ] || { echo "$0: $mini/$s: no scene" >&2; exit 2; }
    ln -sfn "$mini/$s" "$work/cache/datagen/mini-s0/$s"
  done
  # One scene at a time, so an interrupted pass leaves whole scenes behind it.
  for s in $scenes; do
    timed "$work/bench_$s.time" "$hdr4d" bench run paper --store "$work/paper.sqlite" \
      --cache "$work/cache" --methods $methods --scenes "$s" --seeds 0 \
      --iterations "$iterations" --threads "$threads" --series-points 50 --keep-checkpoints \
      --any-code-version \
      > "$work/bench_$s.log" 2>&1 || echo "  $s: bench run failed, see $work/bench_$s.log"
    echo "  $s: $(tail -n 1 "$work/bench_$s.log")"
  done
  # --iterations relabels the runs (e.g. 100it): the table shows that budget.
  "$hdr4d" bench table paper --store "$work/paper.sqlite" --out "$work/tables" \
    --budget "${iterations}it" > /dev/null
  echo "  tables: $work/tables"
fi

stack() {  # OUT IN...: the images that exist side by side (ffmpeg); says which were missing
  local out="$1"
  shift
  local args=() n=0
  for f in "$@"; do
    if [ -f "$f" ]; then
      args+=(-i "$f")
      n=$((n + 1))
    else
      echo "  $out: no $f (its panel left out)"
    fi
  done
  (( n >= 2 )) || { echo "  $out: fewer than two images, not written"; return; }
  ffmpeg -loglevel error -y "${args[@]}" -filter_complex "hstack=inputs=$n" "$out"
  echo "  $out"
}

if [[ " $parts " == *" sides "* ]]; then
  echo "== 3. side-by-side PNGs at ${iterations}it (truth | HexPlane | HDR-HexPlane LDR | LDR+HDR |" \
    "HDR-4DGS LDR | 4DGS): $work/sides"
  mkdir -p "$work/sides"
  d="$work/dnerf"
  first="$(ls "$d/hexplane/renders/test" 2> /dev/null | grep '\.png$' | head -n 1 || true)"
  [ -n "$first" ] && stack "$work/sides/dnerf_lego.png" \
    "$shared/data/dnerf_lego_tiny/images/$first" "$d/hexplane/renders/test/$first" \
    "$d/4dgs/renders/test/$first"
  # The bench runs: RUNS/<id>/spec.json labels each run (method, supervision, scene, budget).
  for s in $scenes; do
    declare -A dir=()
    for spec in "$work"/paper.sqlite.runs/*/spec.json; do
      [ -d "$(dirname "$spec")/renders" ] || continue
      key="$(python3 -c 'import json,sys; l=json.load(open(sys.argv[1]))["labels"][0]
print(l["scene"], l["budget"], l["method"] + "/" + l["supervision"])' "$spec")"
      read -r scene budget row <<< "$key"
      [[ $scene == "$s" && $budget == "${iterations}it" ]] && dir["$row"]="$(dirname "$spec")/renders"
    done
    first="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["frames"][0]["file_path"])' \
      "$mini/$s/transforms_test.json")"
    name="$(basename "$first")"
    stack "$work/sides/${s}_${iterations}it.png" "$mini/$s/$first" \
      "${dir[HexPlane/ldr]:-none}/$name" "${dir[HDR-HexPlane/ldr]:-none}/$name" \
      "${dir[HDR-HexPlane/ldr+hdr]:-none}/$name" "${dir[hdr4dgs/ldr]:-none}/$name" \
      "${dir[4dgs/ldr]:-none}/$name"
    unset dir
  done
fi
