#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (GoogleTest through CTest).
# Pass a CTest regex to run one module: scripts/test.sh core/
#
# Then the SIMD kernels' tests run again on the other SIMD targets this CPU has, through
# HDR4D_SIMD_TARGETS (README): AVX2 where the CPU has AVX-512, and the scalar baseline, so one
# machine proves every path its users' machines may take, not only the one it picks itself.
# Those passes run the tests of the code that dispatches (the Highway kernels of method/ and
# HexPlane's dense products in baselines/hexplane/): the rasteriser, preprocessing, the Dynamic
# Tone Mapper's tone tables, Adam, the losses and the batch gradients through all of them, and
# the appearance MLP's products, under a minute per target on two cores. Not the rest of
# method/ (its training runs drive the same kernels end to end): all of method/ took 2.5 min
# under AVX2 and 4 min under scalar, which would take CI (22 min) close to 30. Nor
# core/: it is built once for the x86-64 baseline and dispatches nothing, so it would run the
# same code again. With a regex, the passes run the tests it selects instead.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DHDR4D_BUILD_TESTS=ON
BUILD_DIR=${HDR4D_BUILD_DIR:-build}
KERNEL_TESTS='^(method/(RasterBlend|Backends/RasterBlendCases|SimdDispatch|Render[.]|Preprocess[.]|DynamicToneMapper|Adam|AllFinite|FusedStep|PhotometricLoss|HdrLoss|HdrColorStage|BatchGradients)|baselines/HexPlaneDense)'
status=0
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" ${1:+-R "$1"} || status=1

# The target the first pass ran (the best this CPU has, unless HDR4D_SIMD_TARGETS was set), as
# `hdr4d --version` names it.
HDR4D="$BUILD_DIR/cli/hdr4d"
first=$("$HDR4D" --version | sed -n 's/.*SIMD target: \([A-Za-z0-9_]*\).*/\1/p') || true
exercised="${first:-?} (${1:-every test})"
for target in avx2 scalar; do
  [ "$target" = "${first,,}" ] && continue  # the first pass ran it
  # hdr4d refuses a target the CPU lacks.
  HDR4D_SIMD_TARGETS=$target "$HDR4D" --version >/dev/null 2>&1 || continue
  echo "== the kernel tests again with HDR4D_SIMD_TARGETS=$target"
  start=$SECONDS
  HDR4D_SIMD_TARGETS=$target ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" \
    -R "${1:-$KERNEL_TESTS}" || status=1
  exercised+=", ${target^^} (${1:-the kernel tests}, $((SECONDS - start)) s)"
done
echo "SIMD targets exercised: $exercised"
exit $status
