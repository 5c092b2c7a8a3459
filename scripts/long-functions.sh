#!/usr/bin/env bash
# Lists the functions longer than N lines (default 80), longest first, from Universal Ctags'
# start and end lines: `bash scripts/long-functions.sh [N] [FOLDER...]`. Test files (*_test.cpp,
# test helpers) are left out; the SIMD kernels that stay long on purpose say so in a comment
# containing "long on purpose" within the 3 lines above them, and are listed apart.
set -euo pipefail
cd "$(dirname "$0")/.."
LIMIT=${1:-80}; shift || true
FOLDERS=("$@"); [ ${#FOLDERS[@]} -eq 0 ] && FOLDERS=(core method baselines datagen calibration benchmark cli)
command -v ctags >/dev/null || { echo "long-functions: needs universal-ctags (apt-get install universal-ctags)" >&2; exit 2; }
find "${FOLDERS[@]}" -name '*.cpp' ! -name '*_test.cpp' ! -name '*test_util*' ! -name 'testing.cpp' |
  sort | xargs ctags --languages=C++ --kinds-C++=f --fields=+ne -o - 2>/dev/null |
  awk -F'\t' -v limit="$LIMIT" '{
      line = ""; end = "";
      for (i = 4; i <= NF; i++) { if ($i ~ /^line:/) line = substr($i, 6); if ($i ~ /^end:/) end = substr($i, 5) }
      if (line != "" && end != "" && end - line + 1 > limit) print end - line + 1, $2 ":" line, $1
    }' |
  sort -rn | while read -r n loc name; do
    file=${loc%%:*}; at=${loc##*:}
    from=$(( at > 3 ? at - 3 : 1 ))
    if sed -n "${from},${at}p" "$file" | grep -q "long on purpose"; then
      echo "$n $loc $name (SIMD kernel, long on purpose)"
    else
      echo "$n $loc $name"
    fi
  done
