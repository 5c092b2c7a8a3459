#include "method/train/content_views.h"

#include <algorithm>
#include <cstdint>

namespace hdr4d::method {

std::optional<double> ContentViews(const std::vector<Eigen::Vector3f>& points,
                                   const std::vector<Camera>& cameras, int max_points) {
  if (points.empty() || cameras.empty() || max_points <= 0) return std::nullopt;
  const std::size_t stride =
      std::max<std::size_t>(1, (points.size() + max_points - 1) / std::size_t(max_points));
  std::vector<Eigen::Vector3d> sample;
  for (std::size_t i = 0; i < points.size(); i += stride)
    sample.push_back(points[i].cast<double>());
  std::vector<std::uint8_t> seen_by_any(sample.size(), 0);
  std::int64_t seen_total = 0;  // (point, camera) pairs
  for (const Camera& camera : cameras) {
    const PinholeIntrinsics& k = camera.intrinsics;
    for (std::size_t i = 0; i < sample.size(); ++i) {
      const auto uvd = camera.Project(sample[i]);  // nullopt behind the camera
      if (!uvd || !((*uvd)[0] >= 0 && (*uvd)[0] <= k.width && (*uvd)[1] >= 0 &&
                    (*uvd)[1] <= k.height))
        continue;
      ++seen_total;
      seen_by_any[i] = 1;
    }
  }
  const auto content = std::count(seen_by_any.begin(), seen_by_any.end(), std::uint8_t{1});
  if (content == 0) return std::nullopt;
  const double mean_seen = double(seen_total) / double(cameras.size());
  return double(content) / mean_seen;  // >= 1: no camera sees more than `content`
}

}  // namespace hdr4d::method
