#include "method/train/initialise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/util/error.h"
#include "method/gaussian/constants.h"

namespace hdr4d::method {
namespace {

TEST(Initialise, NearestNeighbourDistancesMatchBruteForce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Eigen::Vector3f> points(700);
  for (auto& p : points) p = {u(rng), u(rng), 0.2f * u(rng)};  // flat cloud: uneven cells
  points.push_back(points[5]);                                 // a duplicate: distance 0, floored
  const std::vector<float> fast = MeanSquaredDistanceToThreeNearest(points);
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::vector<float> d;
    for (std::size_t j = 0; j < points.size(); ++j)
      if (j != i) d.push_back((points[j] - points[i]).squaredNorm());
    std::partial_sort(d.begin(), d.begin() + 3, d.end());
    const float expected = std::max((d[0] + d[1] + d[2]) / 3.0f, 1e-7f);
    ASSERT_NEAR(fast[i], expected, 1e-6f * std::max(1.0f, expected)) << i;
  }
}

TEST(Initialise, RandomCloudFollowsTheReference) {
  InitOptions options;
  options.num_random_points = 2000;
  options.seed = 1;
  const GaussianModel m = InitialiseGaussians(std::nullopt, options);
  ASSERT_EQ(m.size(), 2000u);
  EXPECT_EQ(m.Validate(), "");
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      ASSERT_LE(std::abs(m.xyz[i * 3 + a]), 1.3f);
    }
    ASSERT_GE(m.t[i], -0.1f);
    ASSERT_LE(m.t[i], 1.1f);
    ASSERT_NEAR(std::exp(2 * m.log_scales[i * 4 + 3]), 0.2f, 1e-6);  // Sigma_tt = T / 5
    ASSERT_NEAR(1 / (1 + std::exp(-m.opacity_logit[i])), 0.1f, 1e-6);
    ASSERT_EQ(m.rot_left[i * 4], 1.0f);
    ASSERT_EQ(m.rot_right[i * 4 + 1], 0.0f);
    // Grey: colour = C0 * dc + 0.5 = 0.5.
    ASSERT_NEAR(kShC0 * m.color_dc[i * 3] + kColorOffset, 0.5f, 1e-6);
  }
  // Same seed, same model.
  EXPECT_EQ(InitialiseGaussians(std::nullopt, options).xyz, m.xyz);
}

TEST(Initialise, PointCloudColoursAndTimesAreUsed) {
  PointCloud cloud;
  for (int i = 0; i < 10; ++i) {
    cloud.positions.emplace_back(0.1f * i, 0, 0);
    cloud.colors.emplace_back(0.9f, 0.2f, 0.1f);
    cloud.times.push_back(0.05f * i);
  }
  InitOptions options;
  const GaussianModel m = InitialiseGaussians(cloud, options);
  ASSERT_EQ(m.size(), 10u);
  EXPECT_FLOAT_EQ(m.t[3], 0.15f);
  EXPECT_NEAR(kShC0 * m.color_dc[2 * 3 + 0] + kColorOffset, 0.9f, 1e-6);
  EXPECT_NEAR(kShC0 * m.color_dc[2 * 3 + 2] + kColorOffset, 0.1f, 1e-6);
  // Points on a line 0.1 apart: interior points' 3 nearest are at 0.1, 0.1, 0.2.
  EXPECT_NEAR(std::exp(2 * m.log_scales[5 * 4]), (0.01f + 0.01f + 0.04f) / 3, 1e-6);
}

TEST(Initialise, StaticModeHasNoTimeAxis) {
  InitOptions options;
  options.num_random_points = 100;
  options.temporal = false;
  const GaussianModel m = InitialiseGaussians(std::nullopt, options);
  EXPECT_FALSE(m.temporal);
  EXPECT_EQ(m.basis.max_time_degree, 0);
  EXPECT_EQ(m.basis.coefficients(), 16);
  EXPECT_EQ(m.t[0], 0.0f);
  EXPECT_EQ(m.rest_stride(), 15u * 3);
}

TEST(Initialise, BadOptionsAreErrors) {
  InitOptions options;
  options.initial_opacity = 1.0f;
  EXPECT_THROW(InitialiseGaussians(std::nullopt, options), Error);
  options = {};
  options.time_min = 2;
  EXPECT_THROW(InitialiseGaussians(std::nullopt, options), Error);
}

// Under an HDR term the log colours start at the targets' level: one constant added to every DC
// colour, so the median lands on the level and the points' colour differences are kept.
TEST(Initialise, LogColoursShiftToALevelKeepingTheirDifferences) {
  PointCloud cloud;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.05f, 0.95f);
  for (int i = 0; i < 101; ++i) {
    cloud.positions.push_back({u(rng), u(rng), u(rng)});
    cloud.colors.push_back({u(rng), u(rng), u(rng)});
  }
  InitOptions options;
  options.color_mode = ColorMode::kLogHdr;
  GaussianModel m = InitialiseGaussians(cloud, options);
  const GaussianModel before = m;
  const float shift = ShiftLogColoursToLevel(&m, -4.5f);
  std::vector<float> logs;
  for (std::size_t i = 0; i < m.color_dc.size(); ++i) {
    const float was = kShC0 * before.color_dc[i] + kColorOffset;
    const float now = kShC0 * m.color_dc[i] + kColorOffset;
    ASSERT_NEAR(now - was, shift, 1e-4f) << i;
    logs.push_back(now);
  }
  std::nth_element(logs.begin(), logs.begin() + logs.size() / 2, logs.end());
  EXPECT_NEAR(logs[logs.size() / 2], -4.5f, 1e-4f);
  EXPECT_LT(shift, -3.0f);  // the points' colours are 0.05-0.95: log levels of -3 to 0
  EXPECT_EQ(m.xyz, before.xyz);
  EXPECT_EQ(m.opacity_logit, before.opacity_logit);
}

}  // namespace
}  // namespace hdr4d::method
