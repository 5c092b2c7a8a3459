#!/usr/bin/env bash
# Two hdr4d binaries (before and after a change to how `hdr4d train` reads its options) resolve
# the same options: for each flag combination below, one iteration on a small demo scene writes
# the same RUN/config.json with both, or both refuse it; a run started by the old binary resumes
# with the new one and records what the old one records resuming it.
#   bash benchmark/proofs/same_train_options.sh OLD_HDR4D NEW_HDR4D WORKDIR
# Exit status 1 when anything differs.
set -uo pipefail
OLD=$(realpath "$1"); NEW=$(realpath "$2"); WORK=$3
mkdir -p "$WORK"
WORK=$(realpath "$WORK")
status=0
S=$WORK/scene
rm -rf "$S"
"$OLD" make-demo-scene --out "$S" --cameras 3 --size 16 --timestamps 3 --spp 1 > /dev/null 2>&1
"$OLD" synth-ldr --data "$S" > /dev/null 2>&1
printf '{"batch_size": 2, "densify_until": 7, "lambda_dssim": 0.3, "max_gaussians": 900}\n' \
  > "$WORK/mine.json"

cases=(
  ""
  "--method 4dgs"
  "--method 4dgs-hdr"
  "--method hdr-gs"
  "--supervision ldr --hdr-weight 0.3 --seed 7"
  "--supervision ldr+hdr --no-hdr-geometry --hdr-target scene-log"
  "--supervision ldr+hdr --hdr-head --hdr-head-iterations 2"
  "--tone-mapper mlp --context-window 5 --context-size 3 --context-learner lstm"
  "--tone-mapper sigmoid --no-gaussian-branch"
  "--direct-tone-curves --monotone-tone-curves --no-pixel-branch"
  "--pixel-log-epsilon 1e-7 --color-lr 0.01"
  "--no-learn-background --background 0.25"
  "--learn-background --random-points 100"
  "--hdr-target aligned"
  "--context-window 20 --context-size 2"
  "--method hdr-gs --supervision auto"
  "--no-learn-background --learn-background"
  "--densify-from 1 --densify-until 5 --densification-interval 2 --densify-grad-threshold 0.0003"
  "--position-lr-steps 9 --opacity-reset-interval 4 --sh-increase-interval 3"
  "--max-gaussians 500 --batch-size 2 --resolution 2"
  "--test-every 1 --checkpoint-every 1 --max-seconds 100"
  "--config syn/lego"
  "--config real/bed --resolution 1"
  "--config dnerf/trex --iterations 2 --batch-size 1 --method 4dgs"
  "--config $WORK/mine.json --batch-size 3"
  "--method 4dgs --tone-mapper dtm"
  "--hdr-head-iterations 3"
  "--hdr-weight 1e7"
  "--iterations 0"
)

# One iteration on one thread unless the case says otherwise.
defaults() {
  local d=""
  [[ "$1" == *--iterations* ]] || d="--iterations 1"
  [[ "$1" == *--threads* ]] || d="$d --threads 1"
  echo "$d"
}

same() {  # label, old file, new file
  if cmp -s "$2" "$3"; then
    printf '%-70s same %s\n' "$1" "$(sha256sum < "$2" | cut -c1-16)"
  else
    printf '%-70s DIFFERENT\n' "$1"; diff <(python3 -m json.tool "$2") <(python3 -m json.tool "$3") | head -20
    status=1
  fi
}

i=0
for c in "${cases[@]}"; do
  i=$((i + 1))
  for side in old new; do
    bin=$OLD; [ "$side" = new ] && bin=$NEW
    rm -rf "$WORK/run-$i-$side"
    # shellcheck disable=SC2086
    "$bin" train --data "$S" --out "$WORK/run-$i-$side" $(defaults "$c") $c \
      > "$WORK/run-$i-$side.log" 2>&1
    echo $? > "$WORK/run-$i-$side.rc"
  done
  rc_old=$(cat "$WORK/run-$i-old.rc"); rc_new=$(cat "$WORK/run-$i-new.rc")
  if [ "$rc_old" != 0 ] || [ "$rc_new" != 0 ]; then
    # Refused: both, each in one line (the words may differ: that is what changed).
    if [ "$rc_old" = "$rc_new" ] && [ ! -e "$WORK/run-$i-new/config.json" ]; then
      printf '%-70s both refuse: %s\n' "${c:-(defaults)}" "$(tail -1 "$WORK/run-$i-new.log" | cut -c1-90)"
    else
      printf '%-70s DIFFERENT exit %s / %s\n' "${c:-(defaults)}" "$rc_old" "$rc_new"
      tail -1 "$WORK/run-$i-old.log" "$WORK/run-$i-new.log"; status=1
    fi
    continue
  fi
  same "${c:-(defaults)}" "$WORK/run-$i-old/config.json" "$WORK/run-$i-new/config.json"
done

# An old run resumed by each binary (copies of one run): the same record, the same checkpoint.
for flags in "--iterations 3 --threads 1" "--iterations 3 --threads 2 --test-every 2" "--hdr-head --threads 1"; do
  rm -rf "$WORK/resume-base"
  "$OLD" train --data "$S" --out "$WORK/resume-base" --iterations 2 --threads 1 --supervision ldr \
    > /dev/null 2>&1
  for side in old new; do
    bin=$OLD; [ "$side" = new ] && bin=$NEW
    rm -rf "$WORK/resume-$side"; cp -r "$WORK/resume-base" "$WORK/resume-$side"
    # shellcheck disable=SC2086
    "$bin" train --out "$WORK/resume-$side" --resume $flags > "$WORK/resume-$side.log" 2>&1 ||
      { echo "resume $flags: $side failed: $(tail -1 "$WORK/resume-$side.log")"; status=1; }
  done
  same "resume $flags: config.json" "$WORK/resume-old/config.json" "$WORK/resume-new/config.json"
  cmp -s "$WORK/resume-old/checkpoint.bin" "$WORK/resume-new/checkpoint.bin" ||
    python3 - "$WORK/resume-old/checkpoint.bin" "$WORK/resume-new/checkpoint.bin" <<'EOF' || status=1
import json, struct, sys
def body(p):  # the checkpoint without its wall-clock field (see same_results.sh)
    b = open(p, "rb").read(); n = struct.unpack("<Q", b[8:16])[0]
    h = json.loads(b[16:16 + n]); h["trainer"].pop("train_seconds", None)
    return json.dumps(h, sort_keys=True).encode() + b[16 + n:-16]
same = body(sys.argv[1]) == body(sys.argv[2])
print(f"{'  checkpoint':<70} {'same' if same else 'DIFFERENT'}")
sys.exit(0 if same else 1)
EOF
done
exit $status
