#!/usr/bin/env bash
# The paper's Table 4 comparison over several seeds: on the built-in analytic HDR scene (the one
# of hdr_proof.sh: radiance over 1e4:1, a dimming sun and a moving lamp, 10 fixed cameras with the
# last held out, exposures 0.125 / 2 / 32 s), train every tone mapper with LDR-only supervision
# once per seed and print mean +- standard deviation of the held-out metrics, and how often each
# mapper is best. Extra arguments go to `hdr4d synth-ldr` (e.g. --gain-drift 1.6 for a camera
# response that changes over time). With SCENE=DIR in the environment, DIR (any dataset, e.g.
# from `hdr4d datagen`) is used instead of the analytic scene.
# Usage: [SCENE=DIR] tone_mapper_seeds.sh OUT [ITERS] [SEEDS] [synth-ldr flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:?usage: tone_mapper_seeds.sh OUT [ITERS] [SEEDS] [synth-ldr flags...]}
ITERS=${2:-3000}
SEEDS=${3:-"0 1 2"}
shift $(( $# < 3 ? $# : 3 ))
HDR4D=${HDR4D:-${HDR4D_BUILD_DIR:-build}/cli/hdr4d}
MAPPERS=(dtm mlp sigmoid reinhard durand)
mkdir -p "$OUT"
if [ -n "${SCENE:-}" ]; then
  [ -f "$SCENE/transforms_train.json" ] || { echo "SCENE=$SCENE: no transforms_train.json" >&2; exit 2; }
  ln -sfn "$(realpath "$SCENE")" "$OUT/scene"
elif [ ! -f "$OUT/scene/transforms_train.json" ]; then
  "$HDR4D" make-demo-scene --out "$OUT/scene" --cameras 10
  "$HDR4D" synth-ldr --data "$OUT/scene" --crf filmic --full-well 20000 --read-noise 0.002 \
    --seed 1 "$@"
fi
for seed in $SEEDS; do
  for tm in "${MAPPERS[@]}"; do
    run="$OUT/$tm-s$seed"
    [ -f "$run/results.json" ] && continue
    echo "== $tm, seed $seed" >&2
    "$HDR4D" train --data "$OUT/scene" --iterations "$ITERS" --densify-until $((ITERS * 5 / 6)) \
      --position-lr-steps "$ITERS" --densify-grad-threshold 1e-3 --seed "$seed" \
      --supervision ldr --tone-mapper "$tm" --out "$run" >/dev/null
  done
done
python3 - "$OUT" "$SEEDS" "${MAPPERS[@]}" <<'PY'
import json, os, statistics, sys
out, seeds, mappers = sys.argv[1], sys.argv[2].split(), sys.argv[3:]
keys = ["psnr", "ssim", "mu_psnr_gt_max", "mu_ssim_gt_max", "pu21_psnr", "pu21_ssim",
        "mu_psnr", "mu_ssim"]
res = {(m, s): json.load(open(os.path.join(out, f"{m}-s{s}", "results.json")))
       for m in mappers for s in seeds}
print(f"{len(seeds)} seeds ({' '.join(seeds)}); mean +- sample standard deviation; "
      "in brackets, on how many seeds the mapper is best")
print("| tone mapper | " + " | ".join(keys) + " | train s |")
print("|" + "---|" * (len(keys) + 2))
for m in mappers:
    cells = []
    for k in keys:
        v = [res[(m, s)]["test"][k] for s in seeds]
        wins = sum(1 for s in seeds
                   if res[(m, s)]["test"][k] >= max(res[(o, s)]["test"][k] for o in mappers))
        sd = statistics.stdev(v) if len(v) > 1 else 0.0
        fmt = "{:.2f} +- {:.2f}" if "psnr" in k else "{:.3f} +- {:.3f}"
        cells.append(fmt.format(statistics.mean(v), sd) + f" ({wins})")
    t = statistics.mean(res[(m, s)]["train_seconds"] for s in seeds)
    print(f"| {m} | " + " | ".join(cells) + f" | {t:.0f} |")
PY
