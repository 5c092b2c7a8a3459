// Reading a HexPlane run folder back (hexplane_run.cpp).
#pragma once

#include <filesystem>

#include "baselines/hexplane/hexplane_model.h"
#include "core/dataset/dataset.h"

namespace hdr4d::baselines::hexplane {

struct LoadedHexPlaneRun {
  HexPlaneConfig config;
  HexPlaneModel model;
  Dataset dataset;
  int resolution = 1;
};

// Throws hdr4d::Error naming the file when the run is incomplete or inconsistent.
LoadedHexPlaneRun LoadHexPlaneRun(const std::filesystem::path& run, int resolution_override = 0);

}  // namespace hdr4d::baselines::hexplane
