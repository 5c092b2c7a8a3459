#include "core/radiometry/camera_pipeline_phone.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace hdr4d {

nlohmann::json PhoneCurve::ToJson() const {
  return {{"white", white}, {"mid", mid}, {"contrast", contrast}, {"toe", kPhoneToe}};
}

PhoneCurve FitPhoneCurve(const FrameStatistics& stats, double exposure_gain) {
  // Logs clamped before exp: percentiles of a float image lie within [ln 1e-6, ln 3.4e38].
  const double log_scale = std::log(std::max(exposure_gain, 1e-300));
  const double log_hi = std::clamp(stats.log_high + log_scale, std::log(1e-3), std::log(1e3));
  const double log_lo = std::min(stats.log_low + log_scale, log_hi);
  PhoneCurve curve;
  curve.white = std::exp(log_hi);
  curve.mid = std::sqrt(std::clamp(std::exp(log_lo - log_hi), 1e-8, 0.25));
  // ln m <= ln 0.5 < 0, so the ratio is finite and positive.
  curve.contrast = std::clamp(std::log(kPhoneToe) / std::log(curve.mid), 0.4, 3.0);
  return curve;
}

std::array<double, 3> WhiteBalanceDrift(int camera, double time, double amplitude,
                                        double period) {
  const double phase = 2 * std::numbers::pi * std::fmod(0.618034 * camera, 1.0);
  const double s = std::sin(2 * std::numbers::pi * time / period + phase);
  return {std::exp(amplitude * s), 1.0, std::exp(-amplitude * s)};
}

}  // namespace hdr4d
