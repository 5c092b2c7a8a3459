// Running Debian's COLMAP 3.8 binary headless on the static images of a capture: SIFT feature
// extraction (CPU, one camera per folder so each rig camera gets its own intrinsics),
// exhaustive matching and incremental mapping. Each step's output goes to a log file in the
// workspace; a failure is an hdr4d::Error naming the step, its last line and a copy of the log
// in a private temporary folder. COLMAP runs as a child that stops when calibrate is stopped.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/util/error.h"

namespace hdr4d {

struct ColmapRunOptions {
  std::string binary = "colmap";
  std::string camera_model = "RADIAL";  // pinhole + k1 k2, what the refinement uses
  int threads = 2;
  int max_image_size = 0;  // --SiftExtraction.max_image_size; 0 = COLMAP's default (3200)
  bool show_progress = true;
  // Further arguments of each step (a rung of calibration/registration_ladder.h).
  std::vector<std::string> extract_args, match_args, map_args;
  // Image pairs to match (names relative to the image root); empty: every pair (exhaustive).
  std::vector<std::pair<std::string, std::string>> match_pairs;
};

// COLMAP ran but left no model (too few matches): a rung of the ladder may still succeed.
class ColmapNoModel : public Error {
 public:
  using Error::Error;
};

// Reconstructs `image_root` (images as <folder>/<file>) into `workspace`; returns the sparse
// model folder with the most registered images. Throws ColmapNoModel when the mapper fails or
// reconstructs nothing, hdr4d::Error when COLMAP is missing or another step fails.
std::filesystem::path RunColmap(const std::filesystem::path& image_root,
                                const std::filesystem::path& workspace,
                                const ColmapRunOptions& options = {});

}  // namespace hdr4d
