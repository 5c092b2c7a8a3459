#!/bin/bash
# A real static capture as a nerfstudio scene: the 11 Sceaux Castle photos of shared/data
# (2832x2128, one camera walked along the facade), posed by COLMAP (SIFT at 1000 px, exhaustive
# matching, the incremental mapper, one SIMPLE_RADIAL camera), undistorted, and written at
# W x H with frames 3 and 8 held out (colmap_to_nerfstudio.py). `hdr4d train --data OUT/scene`
# and `opensplat_time_to_psnr.py --scene OUT/scene --view frame_00003.png` read it (issue 55:
# the static budget and OpenSplat on a capture no rule was set on).
#
#   bash benchmark/proofs/castle_scene.sh OUT [W=240] [H=177] [PHOTOS=../shared/data/sceaux_castle/images]
set -euo pipefail
out=${1:?usage: castle_scene.sh OUT [W] [H] [PHOTOS]}
width=${2:-240}
height=${3:-177}
here=$(cd "$(dirname "$0")" && pwd)
photos=${4:-$here/../../../shared/data/sceaux_castle/images}  # shared/ beside the repository
command -v colmap > /dev/null || { echo "castle_scene.sh: colmap not found (apt install colmap)" >&2; exit 1; }
ls "$photos"/*.JPG > /dev/null 2>&1 || { echo "castle_scene.sh: $photos: no .JPG photos" >&2; exit 1; }
mkdir -p "$out/img" "$out/sparse" "$out/und/txt"
cp "$photos"/*.JPG "$out/img/"
db=$out/db.db
rm -f "$db"
colmap feature_extractor --database_path "$db" --image_path "$out/img" --ImageReader.single_camera 1 \
  --ImageReader.camera_model SIMPLE_RADIAL --SiftExtraction.max_image_size 1000 \
  --SiftExtraction.max_num_features 4000 --SiftExtraction.use_gpu 0 > "$out/colmap.log" 2>&1
colmap exhaustive_matcher --database_path "$db" --SiftMatching.use_gpu 0 >> "$out/colmap.log" 2>&1
colmap mapper --database_path "$db" --image_path "$out/img" --output_path "$out/sparse" >> "$out/colmap.log" 2>&1
[ -f "$out/sparse/0/images.bin" ] || { echo "castle_scene.sh: COLMAP made no model; see $out/colmap.log" >&2; exit 1; }
colmap image_undistorter --image_path "$out/img" --input_path "$out/sparse/0" --output_path "$out/und" \
  --output_type COLMAP >> "$out/colmap.log" 2>&1
colmap model_converter --input_path "$out/und/sparse" --output_path "$out/und/txt" --output_type TXT >> "$out/colmap.log" 2>&1
python3 "$here/colmap_to_nerfstudio.py" "$out/und" "$out/scene" "$width" "$height" 3,8
