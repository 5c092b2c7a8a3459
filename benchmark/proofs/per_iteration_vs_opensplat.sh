#!/usr/bin/env bash
# Per iteration against OpenSplat (issue 55): alternating whole processes in the same minutes,
# each side timed as (t(N2) - t(N1)) / (N2 - N1) of wall seconds, so loading and start-up cancel.
# OpenSplat's side is shared/peers/time_opensplat.sh with --densify-until 100000 (as in every
# earlier pair); hdr4d's is `hdr4d train --iterations N` with the defaults (seed 0, 2 threads) and
# the schedule of a real (20000-iteration) run. Both sides measure the window a real run goes
# through: OpenSplat's schedule does not depend on -n (and --densify-until keeps a short run from
# thinning its Adam steps), while hdr4d scales its densification window and learning-rate decay
# to --iterations, so a bare --iterations 360 densifies at iteration 200 (20k -> 22k Gaussians on
# syn200_20k), which a real run does not before 500. The flags below pin the real run's values.
#
#   bash benchmark/proofs/per_iteration_vs_opensplat.sh HDR4D SCENE PAIRS ISA [N1 N2]
#     ISA: native (each library picks the best code for this CPU) or avx2 (both restricted to
#          AVX2 code on a host that has more: HDR4D_SIMD_TARGETS=avx2 for hdr4d,
#          ATEN_CPU_CAPABILITY=avx2, MKL_ENABLE_INSTRUCTIONS=AVX2 and DNNL_MAX_CPU_ISA=AVX2 for
#          OpenSplat's libtorch). avx2 on an AVX-512 host is a proxy for an AVX2 host, not one:
#          the caches, memory and clock are this host's.
# Env: OPENSPLAT (as time_opensplat.sh), PEERS (default: shared/peers beside the repository).
# Prints one line per pair (OpenSplat ms, hdr4d ms, ratio, OpenSplat's busy flag, hdr4d's Gaussian
# count at N1 and N2: the same when no densification fell in the window) and the median
# ratio. Meaningful only on an otherwise idle machine.
set -euo pipefail
usage="usage: per_iteration_vs_opensplat.sh HDR4D SCENE PAIRS native|avx2 [N1 N2]"
bin=$(realpath "${1:?$usage}")
scene=$(realpath "${2:?$usage}")
pairs=${3:?$usage}
isa=${4:?$usage}
n1=${5:-60}
n2=${6:-360}
here=$(cd "$(dirname "$0")" && pwd)
peers=${PEERS:-$here/../../../shared/peers}
[ -f "$peers/time_opensplat.sh" ] || { echo "per_iteration_vs_opensplat.sh: $peers/time_opensplat.sh not found (set PEERS)" >&2; exit 1; }
[ -x "$bin" ] || { echo "per_iteration_vs_opensplat.sh: $bin is not executable" >&2; exit 1; }
case $isa in
  native) os_env=(); h_env=() ;;
  avx2) os_env=(ATEN_CPU_CAPABILITY=avx2 MKL_ENABLE_INSTRUCTIONS=AVX2 DNNL_MAX_CPU_ISA=AVX2)
        h_env=(HDR4D_SIMD_TARGETS=avx2) ;;
  *) echo "per_iteration_vs_opensplat.sh: ISA must be native or avx2, not '$isa'" >&2; exit 1 ;;
esac
# A 20000-iteration run's densification window and position learning-rate decay (train --help).
real_schedule=(--densify-from 500 --densify-until 15000 --position-lr-steps 15000)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

hdr4d_seconds() {  # iterations -> wall seconds of the whole process
  local s e
  s=$(date +%s.%N)
  env "${h_env[@]}" "$bin" train --data "$scene" --seed 0 --threads 2 --iterations "$1" \
    "${real_schedule[@]}" --out "$work/run" --overwrite > "$work/train.log" 2>&1 ||
    { echo "per_iteration_vs_opensplat.sh: hdr4d train failed; its log:" >&2; tail -5 "$work/train.log" >&2; exit 1; }
  e=$(date +%s.%N)
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["gaussians"])' \
    "$work/run/results.json" > "$work/gaussians_$1"
  awk -v s="$s" -v e="$e" 'BEGIN { printf "%.4f", e - s }'
}

ratios=()
for k in $(seq "$pairs"); do
  line=$(env "${os_env[@]}" bash "$peers/time_opensplat.sh" "$scene" 1 "$n1" "$n2" \
           --densify-until 100000 | grep '^rep')
  os_spi=$(sed -E 's/.* ([0-9.]+) s\/iter.*/\1/' <<< "$line")
  flag=$(awk '{ print $NF }' <<< "$line")
  t1=$(hdr4d_seconds "$n1")
  t2=$(hdr4d_seconds "$n2")
  read -r os_ms h_ms ratio < <(awk -v o="$os_spi" -v a="$t1" -v b="$t2" -v n="$((n2 - n1))" \
    'BEGIN { h = (b - a) / n; printf "%.1f %.2f %.2f\n", 1000 * o, 1000 * h, o / h }')
  g1=$(cat "$work/gaussians_$n1"); g2=$(cat "$work/gaussians_$n2")
  echo "pair $k ($isa): OpenSplat $os_ms ms, hdr4d $h_ms ms per iteration: ${ratio}x ($flag;" \
       "hdr4d Gaussians $g1 -> $g2)"
  ratios+=("$ratio")
done
printf '%s\n' "${ratios[@]}" | sort -g |
  awk -v isa="$isa" '{ a[NR] = $1 } END { m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2;
                       printf "median %.2fx over %d pairs (%s)\n", m, NR, isa }'
