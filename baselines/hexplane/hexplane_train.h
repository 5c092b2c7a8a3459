// `hdr4d train --method hexplane|hexplane-hdr|hdr-hexplane`: the grid family trained natively,
// writing the run folder of a Gaussian run (config.json, checkpoint.bin, results.json).
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace hdr4d::baselines::hexplane {

struct HexPlaneTrainOptions {
  std::filesystem::path data, out;
  std::string method = "hexplane";
  std::string supervision = "auto";  // auto, ldr, hdr, ldr+hdr
  int threads = 0;
  int resolution = 1;
  double max_seconds = 0;  // 0: no limit
  float background = 0.0f;
  bool progress = true;
  // Over the reference's values when set (a CPU budget run shrinks the grid and the batch).
  std::optional<int> iterations, batch_rays, time_grid_init, time_grid_final;
  std::optional<std::int64_t> voxels_init, voxels_final, seed;
  std::optional<float> hdr_weight;
};

struct HexPlaneTrainSummary {
  int iterations = 0;
  double train_seconds = 0;
  nlohmann::json test_metrics;
};

HexPlaneTrainSummary TrainHexPlane(const HexPlaneTrainOptions& options);

}  // namespace hdr4d::baselines::hexplane
