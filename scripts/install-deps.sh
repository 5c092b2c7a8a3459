#!/usr/bin/env bash
# Installs every Debian package hdr4d needs. Idempotent and non-interactive: packages that are
# already installed are skipped, and `apt-get update` runs at most once per call.
set -euo pipefail

PACKAGES=(
  # build
  cmake ninja-build g++ pkg-config lld
  # core: images, maths, parallelism, JSON, CLI, logging
  libopenexr-dev libpng-dev libjpeg-dev libtiff-dev libexif-dev libeigen3-dev libtbb-dev
  nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # benchmark harness: the SQLite results store; the report test opens the HTML page in
  # headless Chromium
  libsqlite3-dev chromium
  # bench slurm's test against a real one-node Slurm (scripts/local-slurm.sh)
  slurm-wlm munge
  # method: SIMD kernels with runtime dispatch
  libhwy-dev
  # benchmark/proofs/hostile_sweep.sh makes its odd images with oiiotool (hdr4d itself does not
  # link OpenImageIO: core/image/image_formats.h)
  openimageio-tools
  # hdr4d render --video encodes MP4 with ffmpeg
  ffmpeg
  # hdr4d datagen renders its scenes with Blender (bpy scripts in datagen/blender; they use
  # only bpy and Python's standard library)
  blender
  # hdr4d calibrate: COLMAP 3.8 (CPU SIFT, run headless), Ceres for the rig refinement, OpenCV
  # for checkerboards, undistortion and the CalibrateDebevec cross-check
  colmap libceres-dev libopencv-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
APT_OPTS=(-y -q --no-install-recommends -o DPkg::Lock::Timeout=600)
export DEBIAN_FRONTEND=noninteractive

echo "install-deps: installing ${missing[*]}"
$SUDO apt-get -q -o DPkg::Lock::Timeout=600 update
$SUDO apt-get install "${APT_OPTS[@]}" "${missing[@]}"
echo "install-deps: done"
