#include "method/train/view_directions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace hdr4d::method {
namespace {

Camera LookingAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  Camera c;
  c.intrinsics = PinholeIntrinsics::FromFovX(0.7, 200, 200);
  c.world_from_cam_gl = LookAtWorldFromCamGl(eye, target, Eigen::Vector3d::UnitZ());
  return c;
}

std::vector<Camera> Ring(int n, int frames_each = 1) {
  std::vector<Camera> ring;
  for (int f = 0; f < frames_each; ++f) {
    for (int k = 0; k < n; ++k) {
      const double a = 2 * std::numbers::pi * k / n;
      ring.push_back(LookingAt({4 * std::cos(a), 4 * std::sin(a), 1.0}, Eigen::Vector3d::Zero()));
    }
  }
  return ring;
}

TEST(DistinctViewDirections, ARingCountsEachCameraFartherApartThanTheAngle) {
  EXPECT_EQ(DistinctViewDirections(Ring(20)), 20);  // 18 degrees apart
  EXPECT_EQ(DistinctViewDirections(Ring(12)), 12);
}

// 40 cameras 9 degrees apart: every other one is within 10 degrees of one counted before it.
TEST(DistinctViewDirections, CamerasCloserThanTheAngleCountOnce) {
  EXPECT_EQ(DistinctViewDirections(Ring(40)), 20);
  EXPECT_EQ(DistinctViewDirections(Ring(40), 5.0), 40);
}

// A rig's cameras film many instants from the same places: its frames add no direction.
TEST(DistinctViewDirections, ARigCountsItsCamerasNotItsFrames) {
  EXPECT_EQ(DistinctViewDirections(Ring(4, /*frames_each=*/60)), 4);
}

// A forward-facing walk looks along one direction however far it goes.
TEST(DistinctViewDirections, AForwardFacingWalkIsOneDirection) {
  std::vector<Camera> walk;
  for (int k = 0; k < 50; ++k)
    walk.push_back(LookingAt({0.2 * k, -5, 0}, {0.2 * k, 0, 0}));
  EXPECT_EQ(DistinctViewDirections(walk), 1);
}

TEST(DistinctViewDirections, NoCamerasOrABrokenPoseCountNothing) {
  EXPECT_EQ(DistinctViewDirections({}), 0);
  std::vector<Camera> cameras = Ring(3);
  cameras[1].world_from_cam_gl(0, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(DistinctViewDirections(cameras), 2);
}

}  // namespace
}  // namespace hdr4d::method
