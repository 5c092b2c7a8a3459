// The training loop's state beyond the model and the optimiser (iteration, random state, view
// order, curves, time), saved in the checkpoint so a resumed run continues exactly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

namespace hdr4d::method {

struct LoopState {
  int iteration = 0;
  std::mt19937_64 rng;
  std::vector<std::uint32_t> order;  // current epoch's view order
  std::size_t next = 0;              // position in `order`
  std::vector<double> loss_curve;
  std::vector<double> psnr_curve;  // training-view PSNR of the final LDR image, per iteration
  nlohmann::json test_curve = nlohmann::json::array();  // {"iteration": i, <metric>: ...}
  // --stop-on-val: {"iteration": i, "psnr": mean val PSNR or null, "train_seconds": s}
  nlohmann::json val_curve = nlohmann::json::array();
  double train_seconds = 0;

  // The next training view: a new shuffled order of all views at the start of each epoch.
  std::uint32_t NextView(std::size_t num_views);

  nlohmann::json ToJson() const;
  // The checkpoint's trainer state, checked: values out of range are refused with the file
  // named, never resumed (the checksum catches damage; this catches a writer's mistake).
  void FromJson(const nlohmann::json& j, const std::filesystem::path& path, std::size_t num_views);
};

// Means over at most `blocks` equal runs of consecutive iterations, so results.json stays small
// at any length: {"iteration": last iteration of each block, <name>: mean, ...}.
nlohmann::json CurveBlocks(const std::vector<double>& loss,
                           const std::vector<double>& psnr,
                           int blocks);

}  // namespace hdr4d::method
