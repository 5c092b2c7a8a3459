#!/bin/bash
# A real static capture as a nerfstudio scene: a folder of photos (.jpg, .JPG or .png) posed by
# COLMAP (SIFT at 1000 px, exhaustive matching, the incremental mapper, one SIMPLE_RADIAL
# camera), undistorted, and written at W x H with the frames in HELD held out
# (colmap_to_nerfstudio.py; frames are numbered in the photos' name order). `hdr4d train --data
# OUT/scene` and `opensplat_time_to_psnr.py --scene OUT/scene --view frame_0000N.png` read it
# (issue 55: the rules of the default on captures no rule was set on).
#
#   bash benchmark/proofs/capture_scene.sh OUT PHOTOS W H HELD
#     HELD: comma-separated frame indices, e.g. 3,8
# benchmark/proofs/castle_scene.sh runs it on shared/data's Sceaux Castle photos.
set -euo pipefail
usage="usage: capture_scene.sh OUT PHOTOS W H HELD"
out=${1:?$usage}
photos=${2:?$usage}
width=${3:?$usage}
height=${4:?$usage}
held=${5:?$usage}
here=$(cd "$(dirname "$0")" && pwd)
command -v colmap > /dev/null || { echo "capture_scene.sh: colmap not found (apt install colmap)" >&2; exit 1; }
shopt -s nullglob
list=("$photos"/*.jpg "$photos"/*.JPG "$photos"/*.jpeg "$photos"/*.png)
[ ${#list[@]} -ge 2 ] || { echo "capture_scene.sh: $photos: fewer than two photos (.jpg, .JPG, .jpeg, .png)" >&2; exit 1; }
mkdir -p "$out/img" "$out/sparse" "$out/und/txt"
cp "${list[@]}" "$out/img/"
db=$out/db.db
rm -f "$db"
echo "capture_scene.sh: COLMAP on ${#list[@]} photos (log: $out/colmap.log)"
: > "$out/colmap.log"
# One COLMAP step; a failed one stops here with its name and the log's last lines (under set -e
# it would otherwise end the script without a word: the mapper exits 1 when no model forms).
step() {
  colmap "$@" >> "$out/colmap.log" 2>&1 && return
  echo "capture_scene.sh: colmap $1 failed on $photos; the end of $out/colmap.log:" >&2
  tail -3 "$out/colmap.log" >&2
  exit 1
}
step feature_extractor --database_path "$db" --image_path "$out/img" --ImageReader.single_camera 1 \
  --ImageReader.camera_model SIMPLE_RADIAL --SiftExtraction.max_image_size 1000 \
  --SiftExtraction.max_num_features 4000 --SiftExtraction.use_gpu 0
step exhaustive_matcher --database_path "$db" --SiftMatching.use_gpu 0
step mapper --database_path "$db" --image_path "$out/img" --output_path "$out/sparse"
[ -f "$out/sparse/0/images.bin" ] || { echo "capture_scene.sh: COLMAP made no model; see $out/colmap.log" >&2; exit 1; }
step image_undistorter --image_path "$out/img" --input_path "$out/sparse/0" \
  --output_path "$out/und" --output_type COLMAP
step model_converter --input_path "$out/und/sparse" --output_path "$out/und/txt" --output_type TXT
python3 "$here/colmap_to_nerfstudio.py" "$out/und" "$out/scene" "$width" "$height" "$held"
