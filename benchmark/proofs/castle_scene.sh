#!/bin/bash
# The real Sceaux Castle photos of shared/data (11 photos, 2832x2128, one camera walked along a
# facade) as a nerfstudio scene at W x H, frames 3 and 8 held out (capture_scene.sh).
#   bash benchmark/proofs/castle_scene.sh OUT [W=240] [H=177] [PHOTOS=../shared/data/sceaux_castle/images]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:?usage: castle_scene.sh OUT [W] [H] [PHOTOS]}
exec bash "$here/capture_scene.sh" "$out" "${4:-$here/../../../shared/data/sceaux_castle/images}" \
  "${2:-240}" "${3:-177}" 3,8
