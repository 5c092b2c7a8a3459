#include "method/train/tone_curve_watch.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "method/gaussian/constants.h"

namespace hdr4d::method {

std::pair<double, double> ToneCurveInputRange(const GaussianModel& model,
                                              const std::vector<TrainView>& views) {
  double log_e_min = std::numeric_limits<double>::infinity(), log_e_max = -log_e_min;
  for (const TrainView& v : views) {
    if (!(v.exposure > 0)) continue;
    log_e_min = std::min(log_e_min, std::log(v.exposure));
    log_e_max = std::max(log_e_max, std::log(v.exposure));
  }
  if (!std::isfinite(log_e_min)) log_e_min = log_e_max = 0;
  // At most ~30k values: the percentiles of a subsample are plenty for a range to sample.
  const std::size_t n = model.color_dc.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 30000);
  std::vector<float> log_colour;
  log_colour.reserve(n / stride + 1);
  for (std::size_t i = 0; i < n; i += stride) {
    const float v = kShC0 * model.color_dc[i] + 0.5f;  // the DC term's colour (sh4d.h)
    if (std::isfinite(v)) log_colour.push_back(v);
  }
  double lo = 0, hi = 0;
  if (!log_colour.empty()) {
    const auto at = [&](double q) {
      auto it = log_colour.begin() + static_cast<std::ptrdiff_t>(q * (log_colour.size() - 1));
      std::nth_element(log_colour.begin(), it, log_colour.end());
      return static_cast<double>(*it);
    };
    lo = at(0.01);
    hi = at(0.99);
  }
  // A model whose colours all agree still gives the curve the exposures' spread, and at least a
  // unit of x, to be judged on.
  double x_min = lo + log_e_min, x_max = hi + log_e_max;
  if (x_max - x_min < 1) {
    const double mid = 0.5 * (x_min + x_max);
    x_min = mid - 0.5;
    x_max = mid + 0.5;
  }
  return {x_min, x_max};
}

std::string FlatToneCurveWarning(const std::vector<FlatToneCurve>& flat,
                                 const std::string& tone_mapper_kind,
                                 std::pair<double, double> range,
                                 int iteration) {
  static const char* const kChannel[3] = {"red", "green", "blue"};
  std::string which;
  for (std::size_t i = 0; i < flat.size(); ++i) {
    which += fmt::format("{}{} at {:.3f} (varies by {:.1e} at time {:.1f})",
                         i == 0 ? "" : (i + 1 == flat.size() ? " and " : ", "),
                         kChannel[flat[i].channel], flat[i].level, flat[i].spread, flat[i].time);
  }
  return fmt::format(
      "train: iteration {}: the {} tone curve{} {} flat over the inputs this scene gives {} (log "
      "radiance + log exposure in [{:.1f}, {:.1f}]): {}. No LDR loss has a gradient through a "
      "flat curve, so those LDR channels will keep that value. The unconstrained curve of "
      "HDR-GS does this under the joint LDR+HDR term on some scenes; --monotone-tone-curves "
      "keeps it rising, and `hdr4d tone-curves --run RUN` draws it",
      iteration, tone_mapper_kind, flat.size() > 1 ? "s" : "", flat.size() > 1 ? "are" : "is",
      flat.size() > 1 ? "them" : "it", range.first, range.second, which);
}

}  // namespace hdr4d::method
