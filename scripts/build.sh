#!/usr/bin/env bash
# Configures and builds hdr4d (Release, Ninja) into build/ (or $HDR4D_BUILD_DIR).
# Extra arguments go to CMake, e.g. -DHDR4D_BUILD_BENCHMARKS=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${HDR4D_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"
