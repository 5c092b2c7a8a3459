#!/usr/bin/env bash
# Time to quality (issue 55): `hdr4d train --reference` against a candidate configuration on one
# scene, alternating whole processes (reference, candidate, reference, ...) in the same minutes,
# one at a time, under nice. Speed is the CPU time (user + sys) of each whole `hdr4d train`
# process (GNU time), not wall time: on a loaded host the CPU time is what the run itself cost.
# Quality comes from the same runs' RUN/results.json: held-out LDR PSNR, aligned mu-PSNR and the
# HDR log-log slope where the scene has HDR ground truth.
#   bash benchmark/proofs/time_to_quality.sh HDR4D SCENE WORKDIR ITERATIONS "SEEDS" "CANDIDATE FLAGS" [NAME]
# Prints one TSV row per run: scene, name, seed, cpu_s, iterations, gaussians, psnr,
# mu_psnr_aligned, hdr_log_slope, stopped; appends them to WORKDIR/time_to_quality.tsv.
# Resumes: a run whose (scene, name, seed) row is already in that TSV is not run again, so an
# interrupted suite is continued by running the same command (delete the row to redo one).
# benchmark/proofs/default_vs_reference.py turns the TSV into the comparison table.
set -euo pipefail
BIN=$(realpath "$1"); SCENE=$(realpath "$2"); WORK=$3; ITERS=$4; SEEDS=$5; FLAGS=$6
NAME=${7:-candidate}
mkdir -p "$WORK"
TSV="$WORK/time_to_quality.tsv"
[ -f "$TSV" ] || printf 'scene\tname\tseed\tcpu_s\titerations\tgaussians\tpsnr\tmu_psnr_aligned\thdr_log_slope\tstopped\n' > "$TSV"

one() {  # name seed flags...
  local name=$1 seed=$2; shift 2
  local run="$WORK/$(basename "$SCENE")-$name-s$seed"
  if awk -F'\t' -v s="$(basename "$SCENE")" -v n="$name" -v d="$seed" \
       '$1 == s && $2 == n && $3 == d { found = 1 } END { exit !found }' "$TSV"; then
    echo "time_to_quality: $(basename "$SCENE") $name seed $seed already in $TSV, not run again"
    return
  fi
  rm -rf "$run"
  /usr/bin/time -f '%U %S' -o "$run.time" nice -n 10 "$BIN" train --data "$SCENE" --out "$run" \
    --seed "$seed" --threads 2 --iterations "$ITERS" "$@" > "$run.log" 2>&1
  python3 - "$run" "$(basename "$SCENE")" "$name" "$seed" >> "$TSV" <<'PY'
import json, sys
run, scene, name, seed = sys.argv[1:5]
u, s = open(run + ".time").read().split()[-2:]
r = json.load(open(run + "/results.json"))
t = r.get("test", {})
def f(k):
    v = t.get(k)
    return "" if v is None else f"{v:.4f}"
stopped = r.get("stopped", {}).get("reason", "")
print("\t".join([scene, name, seed, f"{float(u) + float(s):.1f}", str(r["iterations"]),
                 str(r["gaussians"]), f("psnr"), f("mu_psnr_aligned"), f("hdr_log_slope"), stopped]))
PY
  tail -n 1 "$TSV"
}

for seed in $SEEDS; do
  one reference "$seed" --reference
  # shellcheck disable=SC2086
  one "$NAME" "$seed" $FLAGS
done
