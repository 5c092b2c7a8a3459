#!/usr/bin/env bash
# The hostile sweep of docs/reliability.md, re-runnable: every case runs one hdr4d command as a
# careless or hostile user would and is judged on what the user sees and what is left on disk:
#   err   exit 1, exactly one stderr line, "hdr4d: error: ...", containing the expected words,
#         and the protected files byte for byte as before
#   ok    exit 0 (a valid edge case that must work)
#   report  exit 1 with the problem named in the command's own report on stdout (dataset check)
# Never a signal (crash), never exit 0 for a mistake, never a changed input.
# Usage: benchmark/proofs/hostile_sweep.sh HDR4D_BINARY WORK_DIR
set -uo pipefail
B=$(realpath "$1"); W=$2
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 2
tried=0; held=0; failed_cases=()

snapshot() { find S R -type f ! -name .hdr4d-lock -print0 2>/dev/null | sort -z | xargs -0 sha256sum 2>/dev/null; }

# case KIND "words" args...
case_() {
  local kind=$1 words=$2; shift 2
  tried=$((tried + 1))
  local before; before=$(snapshot)
  local err rc out
  out=$("$B" "$@" 2>"$W/.err"); rc=$?; err=$(cat "$W/.err")
  local after; after=$(snapshot)
  local lines; lines=$(printf '%s' "$err" | grep -c '' || true)
  local ok=1 why=""
  if [ "$kind" = ok ]; then
    [ $rc -eq 0 ] || { ok=0; why="exit $rc: $err"; }
  elif [ "$kind" = report ]; then
    [ $rc -eq 1 ] || { ok=0; why="exit $rc"; }
    printf '%s' "$out" | grep -qiF -- "$words" || { ok=0; why="$why; report lacks '$words'"; }
  else
    [ $rc -eq 1 ] || { ok=0; why="exit $rc"; }
    [ "$lines" -eq 1 ] || { ok=0; why="$why; $lines stderr lines"; }
    case "$err" in "hdr4d: error: "*) ;; *) ok=0; why="$why; not hdr4d's line" ;; esac
    if [ -n "$words" ] && ! printf '%s' "$err" | grep -qiF -- "$words"; then ok=0; why="$why; no '$words'"; fi
  fi
  [ "$before" = "$after" ] || { ok=0; why="$why; inputs changed"; }
  if [ $ok -eq 1 ]; then held=$((held + 1)); else failed_cases+=("$* -> $why"); fi
}

"$B" make-demo-scene --out S --cameras 4 --size 32 --timestamps 4 --spp 1 >/dev/null 2>&1
"$B" synth-ldr --data S >/dev/null 2>&1
"$B" train --data S --out R --iterations 30 --threads 1 >/dev/null 2>&1
printf 'not json' > broken.json; printf '[' > open.json
python3 -c "print('['*100000 + ']'*100000)" > deep.json
mkdir -p empty; : > empty.png

# datagen (no Blender needed for its mistakes)
case_ err "unknown scene" datagen --scene nosuch --out G1
case_ err "--preset" datagen --preset huge --out G1
case_ err "--seed" datagen --seed -1 --out G1
case_ err "--threads" datagen --threads -3 --out G1
case_ err "--width" datagen --width -5 --out G1
case_ err "--crf" datagen --crf "" --out G1
case_ err "--full-well" datagen --full-well -1 --out G1
case_ err "--read-noise" datagen --read-noise 2 --out G1
case_ err "blender" datagen --blender /nonexistent/blender --out G2
case_ err "--samples" datagen --samples abc --out G1
# tone-curves
case_ err "not found" tone-curves --run nosuch
case_ err "--times" tone-curves --run R --times a,b
case_ err "--times" tone-curves --run R --times 2
case_ err "--samples" tone-curves --run R --samples 1
case_ err "--x-min" tone-curves --run R --x-min nan
case_ err "refusing" tone-curves --run R --out S/images
case_ err "refusing" tone-curves --run R --out S/hdr
case_ok() { case_ ok "" "$@"; }
case_ok tone-curves --run R --out TC --samples 2 --times 0
# export-ply
case_ err "not found" export-ply --run nosuch --out x.ply
case_ err "refusing" export-ply --run R --out S/point3d.ply
case_ err "refusing" export-ply --run R --out R/checkpoint.bin
case_ err "refusing" export-ply --run R --out S/transforms_train.json
case_ err "" export-ply --run R --out /proc/forbidden/x.ply
case_ok export-ply --run R --out model.ply
# dataset preview / check
case_ err "refusing" dataset preview S --out S/images/p.png
case_ err "refusing" dataset preview S --out S/hdr/cam00_t000.exr
case_ err "--camera" dataset preview S --out p.png --camera -4
case_ err "--columns" dataset preview S --out p.png --columns 0
case_ err "not found" dataset preview nosuch --out p.png
case_ err "" dataset preview S --out p.png --camera 99
case_ok dataset preview S --out p.png
case_ report "not a folder" dataset check deep.json
case_ report "transforms_train.json: file not found" dataset check empty
# bench
case_ err "" bench run broken.json --store st.db
case_ err "" bench run deep.json --store st.db
case_ err "" bench run open.json --store st.db
case_ err "" bench run nosuch-suite --store st.db
case_ err "--jobs" bench run ci --store st.db --jobs 0
case_ err "--seeds" bench run ci --store st.db --seeds -1
case_ err "--iterations" bench run ci --store st.db --iterations 0
case_ err "" bench table ci --store missing.db
case_ err "--protocol" bench table ci --store st.db --protocol max
case_ err "--format" bench table ci --store st.db --format xls
case_ err "" bench table ci --store S/transforms_train.json
case_ err "" bench pareto ci --store missing.db --out P
case_ err "" bench report ci --store missing.db --out r.html
case_ err "" bench submit --store st2.db --method m --scene S --renders nosuch
case_ err "" bench submit --store st2.db --method m --scene S --renders empty
case_ err "--supervision" bench submit --store st2.db --method m --scene S --renders R --supervision both
case_ err "" bench stress --case nosuch --out SW
case_ err "" bench collect nosuch --store st.db
case_ err "--index" bench task nosuch --array 0 --index -1
case_ err "" bench slurm nosuch-suite --out SL
# calibrate
mkdir -p cap/static/cam0 cap/sequence/cam0
case_ err "not found" calibrate --capture nosuch --out CAL
case_ err "--stage" calibrate --capture cap --out CAL --stage colour
case_ err "--fps" calibrate --capture cap --out CAL --fps 0
case_ err "--samples" calibrate --capture cap --out CAL --samples 1
case_ err "" calibrate --capture cap --out CAL
case_ err "" calibrate --capture empty.png --out CAL
case_ err "" calibrate --capture S --out CAL2
case_ err "" calibrate --capture cap --out S/images --stage radiometry
case_ err "" calibrate --capture cap --out CAL --colmap-model nosuch
case_ err "" calibrate --capture cap --out CAL --board 9x
[ ! -e CAL ] && [ ! -e CAL2 ] || failed_cases+=("calibrate: a failed calibration left an output folder")

echo "hostile sweep: $tried cases tried, $held held"
for f in "${failed_cases[@]}"; do echo "  FAILED: $f"; done
[ ${#failed_cases[@]} -eq 0 ]
