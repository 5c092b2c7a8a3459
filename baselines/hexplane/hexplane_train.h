// `hdr4d train --method hexplane|hexplane-hdr|hdr-hexplane`: the grid family trained natively,
// writing the run folder of a Gaussian run (config.json, checkpoint.bin, results.json).
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/dataset/dataset.h"

namespace hdr4d::baselines::hexplane {

struct HexPlaneTrainOptions {
  std::filesystem::path data, out;
  std::string method = "hexplane";
  std::string supervision = "auto";  // auto, ldr, hdr, ldr+hdr
  // How the scene's `exposures` are read: unset, seconds (a resumed run: its own); recorded.
  std::optional<ExposureUnit> exposure_unit;
  int threads = 0;
  std::optional<int> resolution;   // 1 unless resumed (then the run's)
  std::optional<float> background;  // 0 unless resumed (then the run's)
  double max_seconds = 0;  // 0: no limit
  bool progress = true;
  // Continue RUN/checkpoint.bin exactly as if never stopped (with the same thread count): the
  // run's config.json gives the scene and every setting; one given that differs is refused.
  bool resume = false;
  int checkpoint_every = 0;  // also save a resumable checkpoint every N iterations (0: at the end)
  // Stop after this many iterations with a resumable checkpoint and no results (an interruption
  // at a known point; 0: none).
  int stop_after = 0;
  // Over the reference's values when set (a CPU budget run shrinks the grid and the batch).
  std::optional<int> iterations, batch_rays, time_grid_init, time_grid_final;
  std::optional<std::int64_t> voxels_init, voxels_final, seed;
  std::optional<float> hdr_weight;
  std::optional<std::string> background_model;  // fixed, learned, environment (background_env.h)
};

struct HexPlaneTrainSummary {
  int iterations = 0;
  double train_seconds = 0;
  nlohmann::json test_metrics;
};

HexPlaneTrainSummary TrainHexPlane(const HexPlaneTrainOptions& options);

}  // namespace hdr4d::baselines::hexplane
