#include "method/train/loop_state.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

std::uint32_t LoopState::NextView(std::size_t num_views) {
  if (next >= order.size()) {
    order.resize(num_views);
    std::iota(order.begin(), order.end(), 0u);
    std::shuffle(order.begin(), order.end(), rng);
    next = 0;
  }
  return order[next++];
}

nlohmann::json LoopState::ToJson() const {
  std::ostringstream rng_state;
  rng_state << rng;
  return {{"iteration", iteration},
          {"rng", rng_state.str()},
          {"order", order},
          {"next", next},
          {"loss_curve", loss_curve},
          {"psnr_curve", psnr_curve},
          {"test_curve", test_curve},
          {"val_curve", val_curve},
          {"train_seconds", train_seconds}};
}

void LoopState::FromJson(const nlohmann::json& j, const fs::path& path, std::size_t num_views) {
  try {
    iteration = j.at("iteration").get<int>();
    std::istringstream rng_state(j.at("rng").get<std::string>());
    rng_state >> rng;
    if (rng_state.fail()) Fail("{}: corrupt checkpoint: unreadable random state", path.string());
    order = j.at("order").get<std::vector<std::uint32_t>>();
    next = j.at("next").get<std::size_t>();
    loss_curve = j.at("loss_curve").get<std::vector<double>>();
    // Checkpoints from before the curves were kept resume with empty ones.
    psnr_curve = j.value("psnr_curve", std::vector<double>{});
    test_curve = j.value("test_curve", nlohmann::json::array());
    val_curve = j.value("val_curve", nlohmann::json::array());
    // --stop-on-val decides on these points: each an iteration and a PSNR (null: unscored),
    // and --grow-on-val on the count (absent from checkpoints before it was kept).
    const auto point_ok = [](const nlohmann::json& e) {
      return e.is_object() && e.contains("iteration") && e["iteration"].is_number_integer() &&
             e.contains("psnr") && (e["psnr"].is_number() || e["psnr"].is_null()) &&
             (!e.contains("gaussians") || e["gaussians"].is_number_unsigned());
    };
    if (!val_curve.is_array() || !std::all_of(val_curve.begin(), val_curve.end(), point_ok))
      Fail("{}: corrupt checkpoint: val_curve is not a list of {{iteration, psnr, gaussians}} "
           "points",
           path.string());
    train_seconds = j.at("train_seconds").get<double>();
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: corrupt checkpoint trainer state: {}", path.string(), e.what());
  }
  const bool order_ok =
      std::all_of(order.begin(), order.end(), [&](std::uint32_t v) { return v < num_views; });
  if (iteration < 0 || !order_ok || next > order.size() || !std::isfinite(train_seconds) ||
      train_seconds < 0 || loss_curve.size() > static_cast<std::size_t>(iteration)) {
    Fail(
        "{}: corrupt checkpoint: trainer state out of range (iteration {}, view order of {} "
        "for {} views, next {}, {} s)",
        path.string(), iteration, order.size(), num_views, next, train_seconds);
  }
}

nlohmann::json CurveBlocks(const std::vector<double>& loss,
                           const std::vector<double>& psnr,
                           int blocks) {
  nlohmann::json curve = {{"iteration", nlohmann::json::array()},
                          {"loss", nlohmann::json::array()},
                          {"train_psnr", nlohmann::json::array()}};
  const std::size_t n = loss.size();
  const std::size_t size = std::max<std::size_t>(1, (n + blocks - 1) / blocks);
  for (std::size_t b = 0; b < n; b += size) {
    const std::size_t e = std::min(n, b + size);
    double l = 0, p = 0;
    for (std::size_t i = b; i < e; ++i) l += loss[i];
    curve["iteration"].push_back(e);
    curve["loss"].push_back(FiniteOrNull(l / (e - b)));
    if (psnr.size() == n) {
      for (std::size_t i = b; i < e; ++i) p += psnr[i];
      curve["train_psnr"].push_back(FiniteOrNull(p / (e - b)));
    }
  }
  return curve;
}

}  // namespace hdr4d::method
