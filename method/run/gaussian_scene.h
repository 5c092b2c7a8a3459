// A known 4D Gaussian scene rendered to a dataset: the ground truth for the engine's own
// proof of correctness. Gaussians move (space-time rotations tilt them in x-t, so their slices
// travel) and rotate, seen by several fixed cameras over time; training from random points
// must recover the renders.
#pragma once

#include <cstdint>
#include <filesystem>

#include "core/dataset/dataset.h"
#include "method/gaussian/gaussian_model.h"

namespace hdr4d::method {

struct GaussianSceneOptions {
  int size = 64;  // image width and height
  int num_gaussians = 60;
  int num_cameras = 12;  // on a ring; every 4th is a test camera
  int num_timestamps = 8;
  std::uint64_t seed = 1;
  // Colours that change with the viewing direction up to this SH degree (0..3): random
  // coefficients of up to ~0.3 in colour per degree, a glossy scene whose views disagree.
  int sh_degree = 0;
  void Validate() const;
};

// The scene's model (LDR colours; with sh_degree 0 every view agrees on a Gaussian's colour).
GaussianModel MakeGaussianSceneModel(const GaussianSceneOptions& options);

// Renders every camera at every timestamp to <root>/images/*.png and writes the dataset JSON,
// in a staging folder moved to `root` when complete; `root` must be new or an empty folder.
Dataset MakeGaussianScene(const GaussianSceneOptions& options, const std::filesystem::path& root);

}  // namespace hdr4d::method
