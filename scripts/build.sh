#!/usr/bin/env bash
# Configures and builds hdr4d (Release, Ninja) into build/ (or $HDR4D_BUILD_DIR).
# Extra arguments go to CMake, e.g. -DHDR4D_BUILD_BENCHMARKS=ON. HDR4D_TARGET=hdr4d builds only
# that target (the demo needs the binary, not the tests).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${HDR4D_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)" ${HDR4D_TARGET:+--target "$HDR4D_TARGET"}
