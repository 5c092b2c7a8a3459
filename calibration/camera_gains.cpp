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
  std::vector<std::vector<std::pair<int, std::array<double, 3>>>> samples;
  for (std::size_t p = 0; p < rig.points.size(); ++p) {
    if (p >= rig.visibility.size()) break;
    std::vector<std::pair<int, std::array<double, 3>>> seen;
    for (int c : rig.visibility[p])
      if (auto s = Sample(rig.cameras[c], hdr[c], rig.points.positions[p].cast<double>())) seen.emplace_back(c, *s);
    if (seen.size() >= 2) samples.push_back(std::move(seen));
  }
  result.points_used = static_cast<int>(samples.size());
  if (samples.size() < 10 || nc < 2) return result;

  std::vector<std::array<double, 3>> log_gain(nc, {0, 0, 0});
  auto disagreement = [&]() {
    std::vector<double> d;
    for (const auto& seen : samples)
      for (int ch = 0; ch < 3; ++ch) {
        double mean = 0;
        for (const auto& [c, v] : seen) mean += v[ch] - log_gain[c][ch];
        mean /= seen.size();
        for (const auto& [c, v] : seen) d.push_back(std::abs(std::exp(v[ch] - log_gain[c][ch] - mean) - 1));
      }
    return Median(d);
  };
  result.disagreement_before = disagreement();
  for (int iteration = 0; iteration < 10; ++iteration) {
    for (int ch = 0; ch < 3; ++ch) {
      std::vector<std::vector<double>> residuals(nc);
      for (const auto& seen : samples) {
        double mean = 0;
        for (const auto& [c, v] : seen) mean += v[ch] - log_gain[c][ch];
        mean /= seen.size();
        for (const auto& [c, v] : seen) residuals[c].push_back(v[ch] - mean);
      }
      double centre = 0;
      for (std::size_t c = 0; c < nc; ++c) centre += log_gain[c][ch] = Median(residuals[c]);
      centre /= nc;
      for (std::size_t c = 0; c < nc; ++c) log_gain[c][ch] -= centre;  // geometric mean 1
    }
  }
  result.disagreement_after = disagreement();
  for (std::size_t c = 0; c < nc; ++c)
    for (int ch = 0; ch < 3; ++ch) result.gain[c][ch] = std::exp(log_gain[c][ch]);
  return result;
}

}  // namespace hdr4d
