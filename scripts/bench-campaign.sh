#!/usr/bin/env bash
# Runs a long benchmark suite a few runs at a time, over as many sessions (and machines) as it
# takes. The working store is outside the repository (default <runs folder>/<suite>.sqlite);
# every finished run is also written as a record file into the repository,
# benchmark/results/<suite>/results/<run id>.json (`hdr4d bench export`; about 20 KB a run,
# written once), and a new session's store starts from those files (`hdr4d bench collect`), so
# committing that folder is what carries the campaign from one machine to the next
# (benchmark/results/README.md). It resumes from whatever the store and the record files hold,
# commits nothing, and stops cleanly:
# at --until a run in progress is interrupted (SIGINT: `bench run` stores nothing half-made and
# redoes that run next time), so the store is consistent whenever the script ends.
#
# Order: the suite's scenes in groups of one base scene (the name before its last '-':
# lego-fixed, lego-ae and lego-phone are "lego"), one group at a time, seeds 0, 1, 2 of every
# configuration of the group before the next group: paired verdicts come per scene as early as
# possible. Runs stored by an earlier session's code version count as done
# (`bench run --any-code-version`; the report lists every code version the store holds).
#
# Usage: bash scripts/bench-campaign.sh SUITE [--runs N] [--until HH:MM] [--seeds 0,1,2]
#          [--hdr4d BIN] [--runs-dir DIR] [--cache DIR] [--store FILE] [--series-points N]
#          [--records DIR] [--scenes A,B] [--methods M1,M2] [--foreground]
#   --runs N      stop after N more runs (default: no limit)
#   --series-points N  curves stored at N points (default 8; 0: every point)
#   --records DIR the run record files' folder (default benchmark/results/<suite>; "none": none)
#   --until HH:MM start no run after this time today, interrupt the one in progress at it
#   --scenes A,B  only these scenes, one at a time in this order (default: every base-scene group)
#   --methods M1,M2  only these suite methods (e.g. one table's rows first: its verdict sooner)
#   --foreground  run here instead of in the background (nice 19, nohup; the log and pid file
#                 go to the runs folder, the script prints where)
# Environment: HDR4D_CAMPAIGN_RUNS (default ~/.cache/hdr4d/campaign) holds each suite's run
# folders and log.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
usage() { sed -n '2,31p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit "${1:-2}"; }
[[ $# -ge 1 && $1 != -* ]] || usage
suite="$1"
shift
runs_left=0 until="" seeds="0,1,2" hdr4d="$root/build/cli/hdr4d" foreground=0 cache=""
runs_dir="" store="" series_points=8 records="" scenes="" methods=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --runs) runs_left="$2"; shift 2 ;;
    --until) until="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --hdr4d) hdr4d="$2"; shift 2 ;;
    --runs-dir) runs_dir="$2"; shift 2 ;;
    --cache) cache="$2"; shift 2 ;;
    --store) store="$2"; shift 2 ;;
    --series-points) series_points="$2"; shift 2 ;;
    --records) records="$2"; shift 2 ;;
    --scenes) scenes="$2"; shift 2 ;;
    --methods) methods="$2"; shift 2 ;;
    --foreground) foreground=1; shift ;;
    -h|--help) usage 0 ;;
    *) echo "bench-campaign: unknown option '$1'" >&2; usage ;;
  esac
done
[[ $runs_left =~ ^[0-9]+$ ]] || { echo "bench-campaign: --runs '$runs_left' must be a count" >&2; exit 2; }
[[ $series_points =~ ^[0-9]+$ ]] || { echo "bench-campaign: --series-points '$series_points' must be a count" >&2; exit 2; }
[[ -x $hdr4d ]] || { echo "bench-campaign: no hdr4d binary at $hdr4d (build it, or give --hdr4d)" >&2; exit 2; }
suite_file="$root/benchmark/suites/$suite.json"
[[ -f $suite_file ]] || suite_file="$suite"
[[ -f $suite_file ]] || { echo "bench-campaign: no suite '$suite' (benchmark/suites/*.json or a file)" >&2; exit 2; }
name="$(basename "$suite_file" .json)"
runs_dir="${runs_dir:-${HDR4D_CAMPAIGN_RUNS:-$HOME/.cache/hdr4d/campaign}/$name}"
store="${store:-$runs_dir/$name.sqlite}"
records="${records:-$root/benchmark/results/$name}"
deadline=0
if [[ -n $until ]]; then
  deadline="$(date -d "$until" +%s)" || { echo "bench-campaign: --until '$until' is not a time" >&2; exit 2; }
  (( deadline > $(date +%s) )) || { echo "bench-campaign: --until $until has passed" >&2; exit 2; }
fi
mkdir -p "$runs_dir" "$(dirname "$store")"
log="$runs_dir/campaign.log"

if (( ! foreground )); then
  args=("$suite_file" --runs "$runs_left" --seeds "$seeds" --hdr4d "$hdr4d" --runs-dir "$runs_dir"
        --store "$store" --series-points "$series_points" --records "$records" --foreground)
  [[ -n $until ]] && args+=(--until "$until")
  [[ -n $cache ]] && args+=(--cache "$cache")
  [[ -n $scenes ]] && args+=(--scenes "$scenes")
  [[ -n $methods ]] && args+=(--methods "$methods")
  nohup nice -n 19 bash "${BASH_SOURCE[0]}" "${args[@]}" >>"$log" 2>&1 &
  echo $! >"$runs_dir/campaign.pid"
  echo "bench-campaign: suite $name in the background (pid $!, nice 19); log $log; store $store"
  # TERM, not INT: bash starts a background command with SIGINT ignored, and a signal ignored on
  # entry cannot be trapped, so `kill -INT` would not reach the script (it did not, stop 64).
  echo "bench-campaign: stop it with: kill -TERM $! (the run in progress resumes next time)"
  exit 0
fi

# Base-scene groups in the suite's order: "lego-fixed,lego-ae,lego-phone" per line.
groups="$(python3 - "$suite_file" <<'EOF'
import json, sys
scenes = [s["name"] for s in json.load(open(sys.argv[1]))["scenes"]]
order, members = [], {}
for s in scenes:
    base = s.rsplit("-", 1)[0] if "-" in s else s
    if base not in members:
        order.append(base)
        members[base] = []
    members[base].append(s)
for base in order:
    print(",".join(members[base]))
EOF
)"
[[ -n $scenes ]] && groups="${scenes//,/ }"

# The runs earlier sessions committed join the store first; each new one is written out as soon
# as it is stored, so an interrupted session loses at most the run in progress.
export_records() {
  [[ $records == none ]] && return 0
  "$hdr4d" bench export "$store" --suite "$name" --out "$records" | sed 's/^/bench-campaign: /'
}
if [[ $records != none && -d $records/results ]]; then
  "$hdr4d" bench collect "$records" --store "$store" | sed 's/^/bench-campaign: /'
fi

child=0
stop() {
  (( child )) && kill -INT "$child" 2>/dev/null
  wait "$child" 2>/dev/null || true
  echo "bench-campaign: $(date -Is) stopped by a signal; the interrupted run resumes next time"
  exit 130
}
trap stop INT TERM HUP
extra=()
[[ -n $cache ]] && extra+=(--cache "$cache")
[[ -n $methods ]] && extra+=(--methods "$methods")
done_runs=0
echo "bench-campaign: $(date -Is) suite $name, store $store, seeds $seeds, runs $( ((runs_left)) && echo "$runs_left" || echo "no limit"), until ${until:-no limit}"
for group in $groups; do
  while :; do
    if (( runs_left > 0 && done_runs >= runs_left )); then
      echo "bench-campaign: $(date -Is) $done_runs runs done: stopping (--runs $runs_left)"; exit 0
    fi
    limit=()
    if (( deadline > 0 )); then
      left=$(( deadline - $(date +%s) ))
      (( left > 0 )) || { echo "bench-campaign: $(date -Is) --until $until reached: stopping"; exit 0; }
      limit=(timeout --signal=INT --kill-after=120 "$left")
    fi
    out="$runs_dir/last-bench-run.txt"
    set +e
    "${limit[@]}" "$hdr4d" bench run "$suite_file" --store "$store" --runs-dir "$runs_dir" \
      --scenes "$group" --seeds "$seeds" --max-runs 1 --any-code-version --series-points "$series_points" --jobs 1 "${extra[@]}" \
      >"$out" 2>&1 &
    child=$!
    wait "$child"
    rc=$?
    child=0
    set -e
    cat "$out"
    if (( rc == 124 || rc == 130 )) || grep -q "interrupted by signal" "$out"; then
      echo "bench-campaign: $(date -Is) stopped at the deadline; the interrupted run is redone next time"
      exit 0
    fi
    made="$(sed -n 's/.*stored already, \([0-9]*\) done now, \([0-9]*\) failed.*/\1 \2/p' "$out" | tail -1)"
    if [[ -z $made ]]; then
      failed_now="$(grep -c '^bench: failed:' "$out" || true)"
      (( failed_now > 0 )) || { echo "bench-campaign: bench run failed (rc $rc), see above"; exit "$rc"; }
      made="0 $failed_now"
    fi
    read -r ok_now failed_now <<<"$made"
    (( ok_now + failed_now > 0 )) || break  # this group is complete: the next one
    (( ok_now > 0 )) && export_records
    done_runs=$(( done_runs + ok_now + failed_now ))
  done
done
echo "bench-campaign: $(date -Is) every run of suite $name is in $store"
