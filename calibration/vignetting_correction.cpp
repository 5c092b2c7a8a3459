#include "calibration/vignetting_correction.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/error.h"

namespace hdr4d {

VignettingCorrection ParseVignettingCorrection(const std::string& text) {
  if (text == "auto") return VignettingCorrection::kAuto;
  if (text == "on") return VignettingCorrection::kAlways;
  if (text == "off") return VignettingCorrection::kNever;
  Fail("--vignetting {}: use auto, on or off", text);
}

std::string ToString(VignettingCorrection mode) {
  switch (mode) {
    case VignettingCorrection::kAuto: return "auto";
    case VignettingCorrection::kAlways: return "on";
    case VignettingCorrection::kNever: return "off";
  }
  return "auto";
}

std::vector<double> VignettingToApply(const std::vector<double>& estimate, const std::vector<double>& standard_error,
                                      VignettingCorrection mode) {
  std::vector<double> out(estimate.size(), 0.0);
  for (std::size_t c = 0; c < estimate.size(); ++c) {
    const double v = estimate[c];
    if (!(v > 0) || !std::isfinite(v) || mode == VignettingCorrection::kNever) continue;
    const double se = c < standard_error.size() ? standard_error[c] : std::numeric_limits<double>::infinity();
    const bool measured = v >= kVignettingApplyFrom && v >= kVignettingSignificance * se;
    if (mode == VignettingCorrection::kAlways || measured) out[c] = v;
  }
  return out;
}

double CornerRadius2(const RigCamera& camera, double u, double v) {
  const double cx = camera.intrinsics.cx, cy = camera.intrinsics.cy;
  const double corner2 = std::max({cx * cx + cy * cy, std::pow(camera.width - cx, 2) + std::pow(camera.height - cy, 2),
                                   std::pow(camera.width - cx, 2) + cy * cy, cx * cx + std::pow(camera.height - cy, 2),
                                   1.0});
  return std::min(1.0, ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / corner2);
}

double VignettingFalloff(const RigCamera& camera, double strength, double u, double v) {
  return std::max(0.1, 1 - strength * CornerRadius2(camera, u, v));
}

namespace {

void CheckSize(const Image& image, const RigCamera& camera) {
  if (image.width() != camera.width || image.height() != camera.height)
    Fail("vignetting correction: camera {}: image {}x{} differs from the rig camera's {}x{}", camera.name,
         image.width(), image.height(), camera.width, camera.height);
}

}  // namespace

Image DevignetteLinear(const Image& hdr, const RigCamera& camera, double strength) {
  CheckSize(hdr, camera);
  Image out = hdr;
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      const float scale = static_cast<float>(1 / VignettingFalloff(camera, strength, x + 0.5, y + 0.5));
      for (int c = 0; c < out.channels(); ++c) out.at(x, y, c) *= scale;
    }
  return out;
}

Image DevignetteDisplay(const Image& ldr, const RigCamera& camera, double strength, const CameraResponse& response) {
  CheckSize(ldr, camera);
  Image out = ldr;
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      const double fall = VignettingFalloff(camera, strength, x + 0.5, y + 0.5);
      for (int c = 0; c < out.channels(); ++c) {
        const double value = out.at(x, y, c);
        if (!(value < 1)) continue;  // saturated stays saturated
        out.at(x, y, c) = static_cast<float>(response.Encode(c, response.Linearize(c, value) / fall));
      }
    }
  return out;
}

}  // namespace hdr4d
