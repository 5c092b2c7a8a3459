#include "calibration/camera_gains.h"

#include <algorithm>
#include <cmath>
#include <optional>

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

// Mean log radiance of a 3x3 window around where the point lands, per channel.
std::optional<std::array<double, 3>> Sample(const RigCamera& camera, const Image& hdr,
                                            const Eigen::Vector3d& point) {
  BundlePose pose;
  const Eigen::Matrix4d cam_from_world = RigidInverse(WorldFromCamCvFromGl(camera.world_from_cam_gl));
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(cam_from_world.topLeftCorner<3, 3>()));
  pose.rotation = aa.angle() * aa.axis();
  pose.translation = cam_from_world.topRightCorner<3, 1>();
  const Eigen::Vector2d uv = ProjectRadial(pose, camera.intrinsics, point);
  if (!uv.allFinite()) return std::nullopt;
  const int x0 = static_cast<int>(std::floor(uv.x())), y0 = static_cast<int>(std::floor(uv.y()));
  if (x0 < 1 || y0 < 1 || x0 >= hdr.width() - 1 || y0 >= hdr.height() - 1) return std::nullopt;
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c) {
    double sum = 0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) sum += hdr.at(x0 + dx, y0 + dy, c);
    if (!(sum > 0)) return std::nullopt;
    out[c] = std::log(sum / 9);
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

CameraGains EstimateCameraGains(const Rig& rig, const std::vector<Image>& hdr) {
  const std::size_t nc = rig.cameras.size();
  HDR4D_CHECK(hdr.size() == nc);
  CameraGains result;
  result.gain.assign(nc, {1.0, 1.0, 1.0});
  // samples[p] = (camera, log rgb) for every camera that saw point p and where it projects.
  GainSamples samples;
  for (std::size_t p = 0; p < rig.points.size(); ++p) {
    if (p >= rig.visibility.size()) break;
    std::vector<std::pair<int, std::array<double, 3>>> seen;
    for (int c : rig.visibility[p])
      if (auto s = Sample(rig.cameras[c], hdr[c], rig.points.positions[p].cast<double>())) seen.emplace_back(c, *s);
    if (seen.size() >= 2) samples.push_back(std::move(seen));
  }
  result.points_used = static_cast<int>(samples.size());
  if (samples.size() < 10 || nc < 2) return result;

  result.disagreement_before = GainDisagreement(samples, LogGains(nc, {0, 0, 0}));
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
