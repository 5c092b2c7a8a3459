#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (GoogleTest through CTest).
# Pass a CTest regex to run one module: scripts/test.sh core/
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DHDR4D_BUILD_TESTS=ON
BUILD_DIR=${HDR4D_BUILD_DIR:-build}
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" ${1:+-R "$1"}
