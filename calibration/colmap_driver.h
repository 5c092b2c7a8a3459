// Running Debian's COLMAP 3.8 binary headless on the static images of a capture: SIFT feature
// extraction (CPU, one camera per folder so each rig camera gets its own intrinsics),
// exhaustive matching and incremental mapping. Each step's output goes to a log file in the
// workspace; a failure is an hdr4d::Error naming the step, the log and its last line.
#pragma once

#include <filesystem>
#include <string>

namespace hdr4d {

struct ColmapRunOptions {
  std::string binary = "colmap";
  std::string camera_model = "RADIAL";  // pinhole + k1 k2, what the refinement uses
  int threads = 2;
  int max_image_size = 0;  // --SiftExtraction.max_image_size; 0 = COLMAP's default (3200)
  bool show_progress = true;
};

// Reconstructs `image_root` (images as <folder>/<file>) into `workspace`; returns the sparse
// model folder with the most registered images. Throws hdr4d::Error when COLMAP is missing,
// fails, or reconstructs nothing.
std::filesystem::path RunColmap(const std::filesystem::path& image_root,
                                const std::filesystem::path& workspace,
                                const ColmapRunOptions& options = {});

}  // namespace hdr4d
