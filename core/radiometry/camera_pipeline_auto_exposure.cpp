#include "core/radiometry/camera_pipeline_auto_exposure.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace hdr4d {
namespace {

// The smoothed meter S over a time-ordered series of (t, L).
std::map<double, double> Smooth(const std::map<double, double>& series, double lag) {
  std::map<double, double> smoothed;
  bool first = true;
  double s = 0, previous_t = 0;
  for (const auto& [t, l] : series) {
    if (first) {
      s = l;  // the camera starts converged
      first = false;
    } else {
      const double alpha = lag > 0 ? 1.0 - std::exp(-(t - previous_t) / lag) : 1.0;
      s += alpha * (l - s);
    }
    smoothed[t] = s;
    previous_t = t;
  }
  return smoothed;
}

}  // namespace

std::vector<double> AutoExposureGains(const std::vector<PipelineView>& views,
                                      const std::string& scope, double lag, double strength) {
  if (views.empty()) return {};
  double reference = 0;
  for (const PipelineView& v : views) reference += v.stats.log_mean;
  reference /= static_cast<double>(views.size());

  const bool rig = scope == "rig";
  // Per meter (the rig, or each camera): time -> (sum of L, count).
  std::map<int, std::map<double, std::pair<double, int>>> sums;
  for (const PipelineView& v : views) {
    auto& cell = sums[rig ? 0 : v.camera][v.time];
    cell.first += v.stats.log_mean;
    ++cell.second;
  }
  std::map<int, std::map<double, double>> meters;
  for (const auto& [meter, by_time] : sums) {
    std::map<double, double> series;
    for (const auto& [t, cell] : by_time) series[t] = cell.first / cell.second;
    meters[meter] = Smooth(series, lag);
  }
  std::vector<double> gains;
  gains.reserve(views.size());
  for (const PipelineView& v : views) {
    const double s = meters.at(rig ? 0 : v.camera).at(v.time);
    // Bounded (e^20 = 5e8) so that a black frame beside bright ones cannot overflow.
    gains.push_back(std::exp(std::clamp(strength * (reference - s), -20.0, 20.0)));
  }
  return gains;
}

}  // namespace hdr4d
