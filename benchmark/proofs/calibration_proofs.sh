#!/usr/bin/env bash
# The real-photo proofs of `hdr4d calibrate` in docs/history/calibration.md: Debevec's memorial
# stack through the radiometry stage, Sceaux castle through the geometry stage (its focal length
# against the photographer's K.txt).
# Usage: bash benchmark/proofs/calibration_proofs.sh [WORK_DIR] [COLMAP_MAX_IMAGE_SIZE]
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"  # the repository root
data="$here/../shared/data"
work="${1:-/tmp/hdr4d-calibration-proofs}"
size="${2:-0}"
hdr4d="$here/build/cli/hdr4d"
rm -rf "$work" && mkdir -p "$work"

# memorial: one camera, one frame, 16 brackets with the exposure times of list.txt.
mem="$work/memorial_capture"
mkdir -p "$mem/sequence/cam0"
k=0; times=()
while read -r file seconds; do
  cp "$data/memorial_exposures/$file" "$mem/sequence/cam0/00000_$k.png"
  times+=("$seconds"); k=$((k + 1))
done < "$data/memorial_exposures/list.txt"
(IFS=,; echo "{\"brackets\": [${times[*]}]}") > "$mem/exposures.json"
"$hdr4d" calibrate --capture "$mem" --out "$work/memorial" --stage radiometry

# sceaux: two "rig cameras" (photos 7100 and 7105), the other nine as hand-held extras.
sc="$work/sceaux_capture"
mkdir -p "$sc/static/camA" "$sc/static/camB" "$sc/static/extra"
cp "$data/sceaux_castle/images/100_7100.JPG" "$sc/static/camA/"
cp "$data/sceaux_castle/images/100_7105.JPG" "$sc/static/camB/"
for f in "$data"/sceaux_castle/images/100_71*.JPG; do
  case "$(basename "$f")" in 100_7100.JPG|100_7105.JPG) ;; *) cp "$f" "$sc/static/extra/" ;; esac
done
"$hdr4d" calibrate --capture "$sc" --out "$work/sceaux" --stage geometry --colmap-max-image-size "$size"
echo "K.txt focal: $(head -1 "$data/sceaux_castle/images/K.txt" | awk '{print $1}') px"
grep '^| cam' "$work/sceaux/report.md"
