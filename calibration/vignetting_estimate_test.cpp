// The vignetting estimate on synthetic samples: four cameras with their own falloff and gain see
// points at radii that differ between cameras; the falloff comes back, the common part included.
#include "calibration/vignetting_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hdr4d {
namespace {

TEST(VignettingEstimate, RecoversEachCamerasFalloffFromSharedPoints) {
  const std::vector<double> truth = {0.10, 0.08, 0.23, 0.21}, gain = {0.0, 0.2, -0.1, 0.15};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> radius2(0, 1), level(-2, 2);
  std::normal_distribution<double> scatter(0, 0.03);  // the texture's scatter between samples
  std::vector<std::vector<VignettingSample>> points;
  for (int p = 0; p < 600; ++p) {
    const double l = level(rng);
    std::vector<VignettingSample> seen;
    for (int c = 0; c < 4; ++c) {
      if ((p + c) % 4 == 0) continue;  // each point seen by three of the four
      const double r2 = radius2(rng);
      seen.push_back({c, l + gain[c] + std::log(1 - truth[c] * r2) + scatter(rng), r2});
    }
    points.push_back(seen);
  }
  const std::vector<double> v = EstimateVignetting(points, 4);
  ASSERT_EQ(v.size(), 4u);
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(v[c], truth[c], 0.02) << c;

  // No falloff: all near zero; too few samples: exactly zero.
  for (auto& seen : points)
    for (VignettingSample& s : seen) s.log_radiance -= std::log(1 - truth[s.camera] * s.r2);
  for (double x : EstimateVignetting(points, 4)) EXPECT_NEAR(x, 0, 0.02);
  points.resize(5);
  for (double x : EstimateVignetting(points, 4)) EXPECT_EQ(x, 0);
}

}  // namespace
}  // namespace hdr4d
