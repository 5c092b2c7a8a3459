#!/usr/bin/env bash
# The hostile sweep of docs/reliability.md, re-runnable: every case runs one hdr4d command as a
# careless or hostile user would and is judged on what the user sees and what is left on disk:
#   err   exit 1, exactly one stderr line, "hdr4d: error: ...", containing the expected words,
#         and the protected files byte for byte as before
#   ok    exit 0 (a valid edge case that must work)
#   report  exit 1 with the problem named in the command's own report on stdout (dataset check)
# Never a signal (crash), never a hang (120 s), never exit 0 for a mistake, never a changed input.
# The second part covers the classes of issue 51 (the second sweep), each with variants.
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
  out=$(timeout 120 "$B" "$@" 2>"$W/.err"); rc=$?; err=$(cat "$W/.err")  # 124: it hung
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

# --- issue 51 -------------------------------------------------------------------------------
check() {  # check "what" COMMAND...: an extra condition on disk, counted as a case
  tried=$((tried + 1))
  if "${@:2}"; then held=$((held + 1)); else failed_cases+=("$1"); fi
}
same() { cmp -s "$1" "$2"; }
printf 'precious\n' > victim; cp victim victim.orig
# 13: inputs that are not regular files are refused by name, never read (no hang)
mkfifo fifo.png fifo.ply
python3 -c "import socket; socket.socket(socket.AF_UNIX).bind('sock.png')"
case_ err "not a regular file" eval /dev/zero S/hdr/cam00_t000.exr
case_ err "not a regular file" eval S/hdr/cam00_t000.exr /dev/zero
case_ err "not a regular file" eval fifo.png S/images/cam00_t000_e0.png
case_ err "not a regular file" eval sock.png S/images/cam00_t000_e0.png
case_ err "not a regular file" synth-ldr /dev/zero --out z.png
cp -r S S13; ln -sf /dev/zero S13/images/cam00_t000_e0.png
case_ report "not a regular file" dataset check S13
case_ err "not a regular file" train --data S13 --out R13 --iterations 2 --threads 1
cp -r S S13b; rm S13b/point3d.ply; ln -s ../fifo.ply S13b/point3d.ply
case_ err "not a regular file" train --data S13b --out R13b --iterations 2 --threads 1
cp -r R R13c; rm -f R13c/.hdr4d-lock; ln -sf /dev/zero R13c/checkpoint.bin
case_ err "not a regular file" render --run R13c --out O13
# 14: RGBA PNGs are read with their RGB as stored; eval ignores alpha
oiiotool --pattern constant:color=0.8,0.6,0.4 32x32 3 --pattern constant:color=0.50196 32x32 1 \
  --chappend --chnames R,G,B,A --attrib oiio:UnassociatedAlpha 1 -d uint8 -o rgba.png
oiiotool --pattern constant:color=0.8,0.6,0.4 32x32 3 -d uint8 -o rgb.png
oiiotool --pattern constant:color=0.8,0.6,0.4,0.2 32x32 4 --attrib oiio:UnassociatedAlpha 1 -d uint16 -o rgba16.png
case_ok eval rgba.png rgb.png --out e14.json
check "14: eval of the right RGB at alpha 128 is not an identical pair" grep -q '"identical_pairs": 1' e14.json
case_ok eval rgba16.png rgb.png --out e14b.json
check "14: 16-bit RGBA at alpha 0.2 scores below 40 dB" python3 -c "import json,sys; p=json.load(open('e14b.json'))['mean']['psnr']; sys.exit(0 if p is None or p > 40 else 1)"
# 11: a symlink planted inside --out is replaced, its target never written
mkdir -p O11 R11; ln -s ../victim O11/cam03_t000_e0.png; ln -s ../victim O11/cam03_t000.exr
ln -s ../victim R11/checkpoint.bin; ln -s ../victim R11/.hdr4d-lock; ln -s ../victim R11/config.json
case_ok render --run R --out O11
case_ok train --data S --out R11 --iterations 2 --threads 1 --overwrite
check "11: a planted link's target was written" same victim victim.orig
check "11: the planted render link is still a link" test ! -L O11/cam03_t000_e0.png
# A link the user names on the command line is written through (issue 11), not replaced.
printf 'other\n' > victim2; mkdir -p T11; ln -s ../victim2 T11/scores.json
case_ok eval S/hdr S/hdr --out T11/scores.json
check "11: a link named on the command line was replaced" test -L T11/scores.json
check "11: a link named on the command line was not written through" grep -q '"mean"' victim2
# 17: a constant HDR truth leaves the log-shape numbers undefined, with the reason
oiiotool --pattern constant:color=2,2,2 32x32 3 -d half -o const.exr
oiiotool --pattern noise:type=uniform:min=0.1:max=4 32x32 3 -d half -o noise.exr
oiiotool --pattern constant:color=0.001,0.001,0.001 17x9 3 -d float -o const2.exr
oiiotool --pattern noise:type=uniform:min=0.1:max=4 17x9 3 -d float -o noise2.exr
case_ok eval noise.exr const.exr --out e17.json
case_ok eval noise2.exr const2.exr --out e17b.json
for f in e17.json e17b.json; do
  check "17: $f gives a number for hdr_log_slope/contrast of a constant truth" \
    python3 -c "import json,sys; p=json.load(open('$f'))['pairs'][0]; sys.exit(1 if 'hdr_log_slope' in p or 'hdr_log_contrast' in p or 'hdr_log_slope' not in p.get('undefined', {}) else 0)"
done
# 19: temporaries of dead writers go when the run folder is opened; SIGHUP leaves none
sh -c 'exit 0' & dead=$!; wait $dead
cp -r R R19; rm -f R19/.hdr4d-lock; head -c 100000 /dev/urandom > "R19/.checkpoint.bin.tmp-$dead-0"
cp "R19/.checkpoint.bin.tmp-$dead-0" "R19/.results.json.tmp-$dead-3"
case_ok train --data S --out R19 --resume --iterations 40 --threads 1
check "19: a completed resume left a dead writer's temporary" test -z "$(ls -A R19 | grep '\.tmp-')"
for sig in HUP TERM INT; do
  timeout 120 "$B" train --data S --out "R19$sig" --iterations 100000 --threads 1 >/dev/null 2>&1 & pid=$!
  sleep 4; kill -"$sig" "$pid"; wait "$pid"
  check "19: SIG$sig left a temporary in the run folder" test -z "$(ls -A "R19$sig" 2>/dev/null | grep '\.tmp-')"
done
# 5: bench stress empties only folders it made
mkdir -p SW5/exposure-1e-4-only; printf 'years of work\n' > SW5/exposure-1e-4-only/thesis.tex
cp -r SW5 SW5b; rm SW5b/exposure-1e-4-only/thesis.tex; ln -s ../../victim SW5b/exposure-1e-4-only/notes
case_ err "refusing to empty" bench stress --out SW5 --case exposure-1e-4-only --threads 1
case_ err "refusing to empty" bench stress --out SW5b --case exposure-1e-4-only --threads 1
check "5: bench stress emptied a folder it did not make" test -f SW5/exposure-1e-4-only/thesis.tex
# 7: values reaching a Slurm script carry no control characters
python3 -c "import json; s=json.load(open('$(dirname "$B")/../../benchmark/suites/ci.json')); s['name']='ci\ntouch pwned'; json.dump(s, open('nl.json','w'))" 2>/dev/null \
  || printf '{"name": "x\\ntouch pwned", "scenes": [], "methods": []}' > nl.json
case_ err "control character" bench slurm ci --out SL7 --partition $'cpu\ntouch pwned'
case_ err "control character" bench slurm ci --out SL7 --account $'a\rb'
case_ err "--account" bench slurm ci --out SL7 --account 'a;touch pwned'
case_ err "--partition" bench slurm ci --out SL7 --partition 'cpu $(touch pwned)'
case_ err "" bench slurm nl.json --out SL7
check "7: a refused bench slurm wrote scripts" test ! -e SL7
check "7: a value became a command" test ! -e pwned
# 1 and 10: bench commands never write over the store or suite they read, nor into a dataset
: > st1.db; cp "$(dirname "$B")/../../benchmark/suites/ci.json" suite1.json 2>/dev/null || cp S/transforms_train.json suite1.json
cp st1.db st1.orig 2>/dev/null
case_ err "refusing" bench report suite1.json --store st1.db --out st1.db
case_ err "refusing" bench report suite1.json --store st1.db --out suite1.json
case_ err "refusing" bench report suite1.json --store st1.db --out S/images/r.html
case_ err "refusing" bench table suite1.json --store st1.db --out S/images
case_ err "refusing" bench table suite1.json --store st1.db --out S/hdr
case_ err "refusing" bench pareto suite1.json --store st1.db --out S/hdr
case_ err "refusing" bench pareto suite1.json --store st1.db --out S/images
check "1: the suite file was replaced" grep -q '"name"' suite1.json
# 9: names from a suite are names, refused where the suite is read (dry runs: nothing is run)
tiny() {  # tiny FILE [python statements on the suite s]: the demo scene, 1 method, 1 seed
  python3 - "$1" "${2:-}" <<'PY'
import json, sys
s = {"name": "tiny", "seeds": [0], "budgets": [{"iterations": 20}],
     "resources": {"cpus": 1, "memory_gb": 1, "minutes": 5},
     "scenes": [{"name": "tiny", "builtin": {"scene": "demo", "flags": {"size": 24, "timestamps": 3,
                 "cameras": 3, "spp": 1}, "synth": {"crf": "filmic", "seed": 1}}}],
     "methods": [{"name": "4dgs", "train": {"method": "4dgs"}}],
     "tables": [{"id": "t", "rows": [{"method": "4dgs", "supervision": "ldr"}]}]}
exec(sys.argv[2])
json.dump(s, open(sys.argv[1], "w"))
PY
}
tiny n9a.json 's["tables"][0]["id"] = "../../x9"'
tiny n9b.json 's["tables"][0]["id"] = "'"$W"'/x9abs"'
tiny n9c.json 's["scenes"][0]["name"] = "../../../x9"'
tiny n9d.json 's["methods"][0]["name"] = "4dgs/ldr"; s["tables"][0]["rows"][0]["method"] = "4dgs/ldr"'
tiny n9e.json 's["variants"] = [{"name": "grad/1e-3"}]'
tiny n9f.json 's["name"] = ".."'
tiny n9g.json 's["scenes"][0]["group"] = "a\\b"'
tiny n9h.json 's["tables"][0]["rows"][0]["method"] = "/etc/passwd"'
case_ err "tables[0].id" bench run n9a.json --store st9.db --dry-run --cache C9
case_ err "tables[0].id" bench table n9b.json --store st9.db --out T9
case_ err "scenes[0].name" bench run n9c.json --store st9.db --dry-run --cache C9
case_ err "methods[0].name" bench slurm n9d.json --out SL9
case_ err "variants[0].name" bench run n9e.json --store st9.db --dry-run --cache C9
case_ err "n9f.json.name" bench report n9f.json --store st9.db --out r9.html
case_ err "scenes[0].group" bench run n9g.json --store st9.db --dry-run --cache C9
case_ err "rows[0].method" bench pareto n9h.json --store st9.db --out P9
check "9: a refused suite left a file" test ! -e x9abs -a ! -e ../x9 -a ! -e SL9 -a ! -e r9.html -a ! -e P9
# 24: a suite planning more runs than the stated limit is refused before anything is planned
tiny n24a.json 's["seeds"] = list(range(10**6))'
tiny n24b.json 's["seeds"] = list(range(101)); s["methods"] = [{"name": "m%d" % i} for i in range(100)]'
case_ err "at most 10000 runs" bench run n24a.json --store st24.db --dry-run --cache C9
case_ err "plans 10100 runs" bench run n24b.json --store st24.db --dry-run --cache C9
# 18: a dry run creates no store
tiny t18.json
case_ok bench run t18.json --store st18/s.db --dry-run --cache C9
check "18: a dry run created the store" test ! -e st18
# 18 and 24: bench collect names the file and key of a bad result, merges the others, exits 1
collect_case() {  # collect_case "what" DIR WORDS...: exit 1, every WORDS in the output, good.json stored
  local dir=$1; shift
  tried=$((tried + 1))
  local out rc=0 ok=1
  out=$(timeout 120 "$B" bench collect "$dir" --store "$dir.db" 2>&1) || rc=$?
  [ $rc -eq 1 ] || ok=0
  for w in "$@"; do printf '%s' "$out" | grep -qF -- "$w" || ok=0; done
  printf '%s' "$out" | grep -q 'json.exception' && ok=0
  python3 -c "import sqlite3,sys; sys.exit(0 if sqlite3.connect('$dir.db').execute(\"select count(*) from runs where id='good'\").fetchone()[0] == 1 else 1)" || ok=0
  if [ $ok -eq 1 ]; then held=$((held + 1)); else failed_cases+=("bench collect $dir -> exit $rc: $out"); fi
}
record() {  # record FILE ID [python statements on the record r]
  python3 - "$1" "$2" "${3:-}" <<'PY'
import json, sys
r = {"id": sys.argv[2], "source": "slurm", "status": "ok", "error": "", "code_version": "v",
     "data_checksum": "c", "frames": [], "labels": [{"suite": "s", "method": "m", "scene": "sc",
     "supervision": "ldr", "seed": 0, "budget": "10it", "variant": ""}]}
exec(sys.argv[3])
json.dump(r, open(sys.argv[1], "w"))
PY
}
mkdir -p J24a/results J24b/results J24c/results
record J24a/results/good.json good; record J24a/results/a-typed.json a-typed 'r["iterations"] = "many"'
record J24a/results/a-exposure.json a-exposure 'r["frames"] = [{"frame": "f", "time": 0, "exposure": "bright"}]'
record J24a/results/a-series.json a-series 'r["series"] = {"loss": "points"}'
collect_case J24a "a-typed.json: key 'iterations'" "key 'exposure'" "key 'loss'" "3 result file(s)"
record J24b/results/good.json good; record J24b/results/misnamed.json someone-else
record J24b/results/path.json path 'r["labels"][0]["scene"] = "../../x"'
collect_case J24b "misnamed.json: key 'id'" "path.json: labels: key 'scene'" "2 result file(s)"
python3 -c "import json; l={'suite':'s','method':'m','scene':'sc','supervision':'ldr','seed':0,'budget':'10it','variant':''}; json.dump({'arrays': [{'tasks': [{'id': 'good', 'labels': [l]}, {'id': 'relabelled', 'labels': [l]}]}]}, open('J24c/plan.json', 'w'))"
record J24c/results/good.json good; record J24c/results/stray.json stray
record J24c/results/relabelled.json relabelled 'r["labels"][0]["method"] = "other"'
collect_case J24c "stray.json: run stray is not in plan.json" "relabelled.json: key 'labels'" "2 result file(s)"
# 23: two bench runs on one store share its runs: each is trained once, stored once
tiny t23.json 's["seeds"] = [0, 1]; s["methods"].append({"name": "hdr4dgs", "train": {"method": "hdr4dgs"}})'
"$B" bench run t23.json --store warm23.db --cache C9 --methods 4dgs --seeds 0 --iterations 1 >/dev/null 2>&1
timeout 600 "$B" bench run t23.json --store st23.db --cache C9 --threads 1 >o23a.txt 2>&1 & p1=$!
timeout 600 "$B" bench run t23.json --store st23.db --cache C9 --threads 1 >o23b.txt 2>&1 & p2=$!
wait $p1; r1=$?; wait $p2; r2=$?
check "23: two bench runs on one store failed" test $r1 -eq 0 -a $r2 -eq 0
check "23: two bench runs on one store made a run twice" test "$(cat o23a.txt o23b.txt | grep -o '[0-9]* done now' | awk '{s += $1} END {print s}')" = 4
check "23: a run folder saw two trainings" test -z "$(for l in st23.db.runs/*/log.txt; do [ "$(grep -c '^\$ .* train ' "$l")" = 1 ] || echo "$l"; done)"
# 22: a store locked for a while is waited for; a result kept while it was locked is stored by
# the next bench run without training again
python3 -c "import sqlite3,time; c=sqlite3.connect('st23.db', isolation_level=None); c.execute('BEGIN IMMEDIATE'); time.sleep(8)" & locker=$!
sleep 1
tiny t22.json 's["seeds"] = [2]'
case_ok bench run t22.json --store st23.db --cache C9 --threads 1
wait $locker
id22=$(python3 -c "import sqlite3; print(sqlite3.connect('st23.db').execute('select run_id from run_labels where seed = 2').fetchone()[0])")
mkdir -p "st22.db.runs/$id22"
python3 - "$id22" <<'PY'
import json, sqlite3, sys
db = sqlite3.connect("st23.db")
run = sys.argv[1]
cols = [d[0] for d in db.execute("select * from runs where id = ?", (run,)).description]
row = dict(zip(cols, db.execute("select * from runs where id = ?", (run,)).fetchone()))
labels = [dict(zip(["suite", "method", "scene", "supervision", "seed", "budget", "variant"], l))
          for l in db.execute("select suite, method, scene, supervision, seed, budget, variant from run_labels where run_id = ?", (run,))]
rec = {k: row[k] for k in ["id", "source", "status", "error", "code_version", "git_describe", "data_checksum", "scene_dir", "run_dir", "iterations", "gaussians"]}
rec.update(config=json.loads(row["config"]), machine=json.loads(row["machine"]), labels=labels, frames=[])
json.dump(rec, open("st22.db.runs/%s/record.json" % run, "w"))
PY
case_ok bench run t22.json --store st22.db --cache C9 --threads 1
check "22: a kept result was trained again" test ! -e "st22.db.runs/$id22/train"
check "22: a kept result was not stored" python3 -c "import sqlite3,sys; sys.exit(0 if sqlite3.connect('st22.db').execute(\"select count(*) from runs where id='$id22'\").fetchone()[0] == 1 else 1)"

# 2: a run's files and renders are inputs of every command that reads the run
"$B" render --run R >/dev/null 2>&1
case_ err "refusing" render --run R --timing R/results.json
case_ err "refusing" render --run R --split train --timing R/renders/test/t.json
case_ err "refusing" export-ply --run R --out R/results.json
case_ err "refusing" export-ply --run R --out R/config.json
case_ err "refusing" export-ply --run R --out R/renders/test/cam03_t000_e0.png
case_ err "refusing" tone-curves --run R --out R/renders/test
case_ok render --run R
# 3: a new run never replaces an earlier one unless asked (--overwrite)
case_ err "--overwrite" train --data S --out R --iterations 5 --threads 1
mkdir -p R3; printf 'x' > R3/checkpoint.bin
case_ err "--resume" train --data S --out R3 --iterations 5 --threads 1
mkdir -p R3b; printf '{}' > R3b/results.json
case_ err "--overwrite" train --data S --out R3b --iterations 5 --threads 1
check "3: a refused train replaced a foreign checkpoint" grep -qx x R3/checkpoint.bin
# 18: resuming a finished run rewrites nothing (case_ compares R byte for byte)
case_ok train --out R --resume --threads 1
# 15: --resume refuses a changed dataset, by name
cp -r S S15; rm -f S15/synthesis.json.tmp*; "$B" train --data S15 --out R15 --iterations 10 --threads 1 >/dev/null 2>&1
cp S15/images/cam00_t000_e0.png keep15.png; cp S15/images/cam01_t000_e0.png S15/images/cam00_t000_e0.png
case_ err "changed" train --out R15 --resume --iterations 20 --threads 1
cp keep15.png S15/images/cam00_t000_e0.png; cp S15/transforms_train.json keep15.json
python3 -c "import json; d=json.load(open('S15/transforms_train.json')); d['frames'].reverse(); json.dump(d, open('S15/transforms_train.json','w'))"
case_ err "frame 0 was" train --out R15 --resume --iterations 20 --threads 1
cp keep15.json S15/transforms_train.json
case_ok train --out R15 --resume --iterations 20 --threads 1
# 4: renders keep the frames' sub-folders (images/camNN/...), eval pairs them by path
cp -r S S4
python3 - <<'PY'
import json, os
for split in ('train', 'test'):
    p = f'S4/transforms_{split}.json'; d = json.load(open(p))
    for f in d['frames']:
        for k in ('file_path', 'exr_file_path'):
            folder, name = os.path.split(f[k]); moved = os.path.join(folder, name[:5], name[6:])
            os.makedirs(os.path.join('S4', folder, name[:5]), exist_ok=True)
            if os.path.exists(os.path.join('S4', f[k])): os.rename(os.path.join('S4', f[k]), os.path.join('S4', moved))
            f[k] = moved
    json.dump(d, open(p, 'w'))
PY
"$B" train --data S4 --out R4 --iterations 10 --threads 1 >/dev/null 2>&1
case_ok render --run R4 --split train --out O4
check "4: renders of frames in sub-folders overwrote each other" test "$(find O4 -name '*.png' | wc -l)" -eq 36
case_ok eval O4 S4/images --out e4.json
check "4: eval did not pair each render with its own camera's truth" python3 -c "import json,sys; p=json.load(open('e4.json'))['pairs']; sys.exit(0 if len(p)==36 and p[0]['name']=='cam00/t000_e0.png' else 1)"
# 6: synth-ldr never replaces LDR images it did not make without --overwrite
cp -r S S6; rm S6/synthesis.json; cp S6/images/cam00_t000_e0.png keep6.png
case_ err "synthesis.json" synth-ldr --data S6
case_err_keep6() { cmp -s keep6.png S6/images/cam00_t000_e0.png; }
check "6: synth-ldr replaced an LDR image it did not make" case_err_keep6
case_ok synth-ldr --data S6 --overwrite
# 18: merge-hdr of brackets clipped everywhere warns that the result is a constant
cp -r S S18
for f in S18/images/*.png; do oiiotool --pattern constant:color=1,1,1 32x32 3 -d uint8 -o "$f"; done
"$B" merge-hdr --data S18 --out M18 2>m18.err >/dev/null
check "18: merge-hdr of clipped brackets said nothing" grep -q "constant" m18.err
# 12 and 20: a huge point cloud under a 3 GB limit, a full disk (a 64 KB file-size limit)
REAL=$B
printf '#!/bin/bash\nulimit -v 3000000; exec "%s" "$@"\n' "$REAL" > small_memory.sh
printf '#!/bin/bash\ntrap "" XFSZ; ulimit -f 64; exec "%s" "$@"\n' "$REAL" > small_disk.sh
chmod +x small_memory.sh small_disk.sh
cp -r S S12
python3 -c "n=3000000; open('S12/point3d.ply','wb').write(b'ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nend_header\n' % n + bytes(12*n))"
B=$W/small_memory.sh
case_ err "--max-gaussians" train --data S12 --out R12 --iterations 5 --threads 1
check "12: a refused start left its run folder" test ! -e R12
case_ok train --data S12 --out R12 --iterations 5 --threads 1 --max-gaussians 2000
B=$REAL
"$W/small_disk.sh" train --data S --out R20 --iterations 5 --threads 1 >/dev/null 2>r20.err; rc=$?
check "20: train on a full disk did not end with exit 1" test $rc -eq 1
check "20: a train that hit a full disk left its run folder" test ! -e R20
mkdir -p R20b; cp R/config.json R20b/
case_ err "no checkpoint.bin" train --out R20b --resume --threads 1
# 24: appended bytes, an ffmpeg pattern in --out, a read-only scene
cp -r R R24; rm -f R24/.hdr4d-lock; printf 'junk' >> R24/checkpoint.bin
case_ err "appended" render --run R24 --out O24
if command -v ffmpeg >/dev/null 2>&1; then
  case_ok render --run R --video 3 --out 'V%02d'
  check "24: render --video --out V%02d made no video" test -e 'V%02d/video.mp4'
fi
if command -v setpriv >/dev/null 2>&1 && setpriv --reuid=65534 --regid=65534 --clear-groups "$B" --version >/dev/null 2>&1; then
  printf '#!/bin/bash\nexec setpriv --reuid=65534 --regid=65534 --clear-groups "%s" "$@"\n' "$REAL" > nobody.sh
  chmod +x nobody.sh; chmod 755 "$W"; B=$W/nobody.sh
  case_ err "read-only" synth-ldr --data S
  B=$REAL
fi

echo "hostile sweep: $tried cases tried, $held held"
for f in "${failed_cases[@]}"; do echo "  FAILED: $f"; done
[ ${#failed_cases[@]} -eq 0 ]
