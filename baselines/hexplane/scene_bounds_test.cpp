#include "baselines/hexplane/scene_bounds.h"

#include <gtest/gtest.h>

#include <random>

namespace hdr4d::baselines::hexplane {
namespace {

// Points filling [1, 3] x [-1, 1] x [0, 0.5] plus a few far strays: the cube sits on the bulk
// (the strays are beyond the 1st..99th percentiles) with its side the longest axis's, widened.
TEST(SceneBounds, CubeAroundTheBulkOfThePoints) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 2000; ++i) points.emplace_back(1 + 2 * u(rng), -1 + 2 * u(rng), 0.5f * u(rng));
  for (int i = 0; i < 5; ++i) points.emplace_back(1000.0f, -1000.0f, 500.0f);
  const std::optional<SceneBox> box = BoxAroundPoints(points);
  ASSERT_TRUE(box);
  EXPECT_NEAR(box->center[0], 2.0f, 0.05f);
  EXPECT_NEAR(box->center[1], 0.0f, 0.05f);
  EXPECT_NEAR(box->center[2], 0.25f, 0.05f);
  EXPECT_NEAR(box->half, 1.2f, 0.05f);  // half of 2, widened by 10% each side
}

TEST(SceneBounds, TooFewOrDegeneratePointsGiveNoBox) {
  EXPECT_FALSE(BoxAroundPoints({}));
  EXPECT_FALSE(BoxAroundPoints(std::vector<Eigen::Vector3f>(7, Eigen::Vector3f(1, 2, 3))));
  EXPECT_FALSE(BoxAroundPoints(std::vector<Eigen::Vector3f>(100, Eigen::Vector3f(1, 2, 3))));
  std::vector<Eigen::Vector3f> nan(100, Eigen::Vector3f(1, 2, 3));
  for (auto& p : nan) p[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(BoxAroundPoints(nan));
}

// Cameras 4 and 6 away from the box centre: the depths hold the box's half diagonal either side.
TEST(SceneBounds, DepthRangeHoldsTheBoxFromEveryCamera) {
  SceneBox box;
  box.center = {1, 0, 0};
  box.half = 1;
  const auto [near, far] =
      DepthRangeOf(box, {Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(1, 6, 0)});
  EXPECT_NEAR(near, 4 - std::sqrt(3.0), 1e-5);
  EXPECT_NEAR(far, 6 + std::sqrt(3.0), 1e-5);
  // A camera inside the box: near stays positive.
  const auto [near_in, far_in] = DepthRangeOf(box, {Eigen::Vector3d(1, 0, 0)});
  EXPECT_GT(near_in, 0.0f);
  EXPECT_GT(far_in, near_in);
}

// A camera at z = 5 looking down -z at the origin (OpenGL convention: the camera looks along its
// -z) sees the point at the origin, not one far to the side nor one behind it.
TEST(SceneBounds, KeepsThePointsACameraSees) {
  Camera c;
  c.intrinsics.width = c.intrinsics.height = 100;
  c.intrinsics.fx = c.intrinsics.fy = 100;
  c.intrinsics.cx = c.intrinsics.cy = 50;
  c.world_from_cam_gl = LookAtWorldFromCamGl({0, 0, 5}, {0, 0, 0});
  const std::vector<Eigen::Vector3f> seen = PointsInAnyView(
      {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(50, 0, 0), Eigen::Vector3f(0, 0, 10)}, {c});
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0], Eigen::Vector3f(0, 0, 0));
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
