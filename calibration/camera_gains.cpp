#include "calibration/camera_gains.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "calibration/vignetting_correction.h"
#include "calibration/vignetting_estimate.h"
#include "core/geometry/camera.h"
#include "core/util/error.h"

namespace hdr4d {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

// Where a rig camera sees a point: its pixel position and depth (nothing behind the camera or
// off the lens model).
struct PointView {
  Eigen::Vector2d uv;
  double pixels_per_unit = 0;  // focal length / depth: how large the surface appears
};

// A rig camera's pose in the bundle's form, computed once per camera (not per point).
struct CameraPose {
  BundlePose pose;
  Eigen::Matrix3d rotation;  // cam_from_world
};

CameraPose PoseOf(const RigCamera& camera) {
  CameraPose out;
  const Eigen::Matrix4d cam_from_world = RigidInverse(WorldFromCamCvFromGl(camera.world_from_cam_gl));
  out.rotation = cam_from_world.topLeftCorner<3, 3>();
  const Eigen::AngleAxisd aa(out.rotation);
  out.pose.rotation = aa.angle() * aa.axis();
  out.pose.translation = cam_from_world.topRightCorner<3, 1>();
  return out;
}

std::optional<PointView> View(const RigCamera& camera, const CameraPose& pose, const Eigen::Vector3d& point) {
  const double depth = (pose.rotation * point + pose.pose.translation).z();
  const Eigen::Vector2d uv = ProjectRadial(pose.pose, camera.intrinsics, point);
  if (!(depth > 0) || !uv.allFinite()) return std::nullopt;
  return PointView{uv, camera.intrinsics.f / depth};
}

// Mean log radiance around `uv` (pixel i spans [i, i + 1)), per channel: over the pixels whose
// centres lie within `radius` of it, or the 3x3 window of the pixel it falls in for a radius
// under 1.5 (what every camera used before the footprint).
std::optional<std::array<double, 3>> Sample(const Image& hdr, const Eigen::Vector2d& uv, double radius) {
  const bool window = radius < 1.5;
  const int x_lo = static_cast<int>(std::floor(window ? uv.x() - 1 : uv.x() - radius));
  const int x_hi = static_cast<int>(std::floor(window ? uv.x() + 1 : uv.x() + radius));
  const int y_lo = static_cast<int>(std::floor(window ? uv.y() - 1 : uv.y() - radius));
  const int y_hi = static_cast<int>(std::floor(window ? uv.y() + 1 : uv.y() + radius));
  if (x_lo < 0 || y_lo < 0 || x_hi >= hdr.width() || y_hi >= hdr.height()) return std::nullopt;
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c) {
    double sum = 0;
    int n = 0;
    for (int y = y_lo; y <= y_hi; ++y)
      for (int x = x_lo; x <= x_hi; ++x) {
        const double dx = x + 0.5 - uv.x(), dy = y + 0.5 - uv.y();
        if (!window && dx * dx + dy * dy > radius * radius) continue;
        sum += hdr.at(x, y, c);
        ++n;
      }
    if (!(sum > 0) || n == 0) return std::nullopt;
    out[c] = std::log(sum / n);
  }
  return out;
}

using GainSamples = std::vector<std::vector<std::pair<int, std::array<double, 3>>>>;
using LogGains = std::vector<std::array<double, 3>>;

// Median over (point, camera) of |radiance / the point's mean - 1| after dividing by the gains.
double GainDisagreement(const GainSamples& samples, const LogGains& log_gain) {
  std::vector<double> d;
  for (const auto& seen : samples)
    for (int ch = 0; ch < 3; ++ch) {
      double mean = 0;
      for (const auto& [c, v] : seen) mean += v[ch] - log_gain[c][ch];
      mean /= seen.size();
      for (const auto& [c, v] : seen) d.push_back(std::abs(std::exp(v[ch] - log_gain[c][ch] - mean) - 1));
    }
  return Median(d);
}

// Each camera's median log residual against the points' mean, over the points of one parity
// (0 or 1; 2 = all), with `log_gain` divided out first.
LogGains MedianResiduals(const GainSamples& samples, const LogGains& log_gain, int parity) {
  const std::size_t nc = log_gain.size();
  LogGains out(nc, {0, 0, 0});
  for (int ch = 0; ch < 3; ++ch) {
    std::vector<std::vector<double>> residuals(nc);
    for (std::size_t p = 0; p < samples.size(); ++p) {
      if (parity != 2 && static_cast<int>(p % 2) != parity) continue;
      double mean = 0;
      for (const auto& [c, v] : samples[p]) mean += v[ch] - log_gain[c][ch];
      mean /= samples[p].size();
      for (const auto& [c, v] : samples[p]) residuals[c].push_back(v[ch] - log_gain[c][ch] - mean);
    }
    for (std::size_t c = 0; c < nc; ++c) out[c][ch] = Median(residuals[c]);
  }
  return out;
}

// Gains whose geometric mean is 1 per channel, from the points of one parity (2 = all).
LogGains SolveLogGains(const GainSamples& samples, std::size_t nc, int parity) {
  LogGains log_gain(nc, {0, 0, 0});
  for (int iteration = 0; iteration < 10; ++iteration) {
    const LogGains step = MedianResiduals(samples, log_gain, parity);
    for (int ch = 0; ch < 3; ++ch) {
      double centre = 0;
      for (std::size_t c = 0; c < nc; ++c) centre += log_gain[c][ch] += step[c][ch];
      centre /= nc;
      for (std::size_t c = 0; c < nc; ++c) log_gain[c][ch] -= centre;
    }
  }
  return log_gain;
}

// Gains from the points of one parity, each camera's remaining median bias on the other's:
// texture and reprojection scatter average out in the median, what is left is the gains' error.
double HeldOutBias(const GainSamples& samples, std::size_t nc) {
  double worst = 0;
  for (int parity = 0; parity < 2; ++parity) {
    const LogGains bias = MedianResiduals(samples, SolveLogGains(samples, nc, parity), 1 - parity);
    for (const auto& b : bias)
      for (const double x : b) worst = std::max(worst, std::abs(std::exp(x) - 1));
  }
  return worst;
}

}  // namespace

double CameraGains::Mean(int camera) const {
  const auto& g = gain[camera];
  return (g[0] + g[1] + g[2]) / 3;
}

CameraGains EstimateCameraGains(const Rig& rig, const std::vector<Image>& hdr, double footprint_pixels,
                                VignettingCorrection vignetting) {
  const std::size_t nc = rig.cameras.size();
  HDR4D_CHECK(hdr.size() == nc);
  CameraGains result;
  result.gain.assign(nc, {1.0, 1.0, 1.0});
  result.footprint_pixels = footprint_pixels;
  // samples[p] = (camera, log rgb) for every camera that saw point p and where it projects.
  std::vector<CameraPose> poses;
  for (const RigCamera& camera : rig.cameras) poses.push_back(PoseOf(camera));
  GainSamples samples;
  std::vector<std::vector<VignettingSample>> falloff;  // the same samples with their radii
  for (std::size_t p = 0; p < rig.points.size(); ++p) {
    if (p >= rig.visibility.size()) break;
    const Eigen::Vector3d point = rig.points.positions[p].cast<double>();
    std::vector<std::pair<int, PointView>> views;
    double smallest = 0;  // pixels per unit of the camera that sees the surface smallest
    for (int c : rig.visibility[p])
      if (auto v = View(rig.cameras[c], poses[c], point)) {
        views.emplace_back(c, *v);
        if (smallest == 0 || v->pixels_per_unit < smallest) smallest = v->pixels_per_unit;
      }
    std::vector<std::pair<int, std::array<double, 3>>> seen;
    std::vector<VignettingSample> radii;
    for (const auto& [c, v] : views) {
      const double radius = footprint_pixels > 0 ? footprint_pixels * v.pixels_per_unit / smallest : 1;
      if (auto s = Sample(hdr[c], v.uv, radius)) {
        seen.emplace_back(c, *s);
        radii.push_back({c, ((*s)[0] + (*s)[1] + (*s)[2]) / 3, CornerRadius2(rig.cameras[c], v.uv.x(), v.uv.y())});
      }
    }
    if (seen.size() >= 2) {
      samples.push_back(std::move(seen));
      falloff.push_back(std::move(radii));
    }
  }
  result.points_used = static_cast<int>(samples.size());
  if (samples.size() < 10 || nc < 2) return result;

  result.disagreement_before = GainDisagreement(samples, LogGains(nc, {0, 0, 0}));
  // The falloff first: the gains are then solved on the samples with it divided out, so that a
  // camera's gain is not its mean falloff over where the points happened to land.
  result.vignetting = EstimateVignetting(falloff, static_cast<int>(nc), &result.vignetting_error);
  result.vignetting_applied = VignettingToApply(result.vignetting, result.vignetting_error, vignetting);
  for (std::size_t p = 0; p < samples.size(); ++p)
    for (std::size_t k = 0; k < samples[p].size(); ++k) {
      const double v = result.vignetting_applied[samples[p][k].first];
      const double log_fall = std::log(std::max(0.1, 1 - v * falloff[p][k].r2));
      for (double& x : samples[p][k].second) x -= log_fall;
    }
  // Iterated: each camera's median residual against the points' mean, the mean then
  // recomputed without the gains found so far.
  const LogGains log_gain = SolveLogGains(samples, nc, 2);
  result.disagreement_after = GainDisagreement(samples, log_gain);
  if (samples.size() >= 20) result.held_out_bias = HeldOutBias(samples, nc);
  for (std::size_t c = 0; c < nc; ++c)
    for (int ch = 0; ch < 3; ++ch) result.gain[c][ch] = std::exp(log_gain[c][ch]);
  return result;
}

}  // namespace hdr4d
