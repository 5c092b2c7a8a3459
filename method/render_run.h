// Rendering a trained run (`hdr4d render`): the run's checkpoint and configuration give the
// model and the scene; each view of a split is rendered and written under its ground truth's
// file name, so `hdr4d eval OUT <scene>/<image folder>` compares them directly.
#pragma once

#include <filesystem>
#include <string>

#include "method/gaussian_model.h"

namespace hdr4d::method {

struct RenderRunOptions {
  std::filesystem::path run;
  std::filesystem::path out;   // default: RUN/renders/<split>
  std::string split = "test";  // train, test or val
  int threads = 0;
};

// Returns the number of images written.
int RenderRun(const RenderRunOptions& options);

// The model of a run's checkpoint (RUN/checkpoint.bin).
GaussianModel LoadRunModel(const std::filesystem::path& run);

}  // namespace hdr4d::method
