#include "calibration/bundle_refinement.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "tests/testing.h"

namespace hdr4d {
namespace {

// Three cameras on an arc looking at a cloud of points around the origin.
BundleProblem Synthetic(std::mt19937& rng) {
  BundleProblem problem;
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 150; ++i) problem.points.emplace_back(u(rng), u(rng), u(rng));
  for (int c = 0; c < 3; ++c) {
    const double angle = (c - 1) * 0.4;
    const Eigen::Vector3d centre(4 * std::sin(angle), 0.3 * c, -4 * std::cos(angle));
    // Look at the origin: camera +Z towards it, +Y down (OpenCV axes).
    const Eigen::Vector3d z = -centre.normalized();
    const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Matrix3d world_from_cam;
    world_from_cam << x, y, z;
    const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
    BundlePose pose;
    const Eigen::AngleAxisd aa(cam_from_world);
    pose.rotation = aa.angle() * aa.axis();
    pose.translation = -cam_from_world * centre;
    pose.fixed = c == 0;
    problem.poses.push_back(pose);
    problem.intrinsics.push_back({500.0 + 20 * c, 320, 240, -0.05, 0.01});
  }
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < static_cast<int>(problem.points.size()); ++i)
      problem.observations.push_back(
          {c, c, i, ProjectRadial(problem.poses[c], problem.intrinsics[c], problem.points[i])});
  return problem;
}

double RotationErrorDegrees(const BundlePose& a, const BundlePose& b) {
  const Eigen::AngleAxisd ra(a.rotation.norm(), a.rotation.normalized());
  const Eigen::AngleAxisd rb(b.rotation.norm(), b.rotation.normalized());
  return Eigen::AngleAxisd(ra.toRotationMatrix().transpose() * rb.toRotationMatrix()).angle() * 180 / M_PI;
}

TEST(BundleRefinement, RecoversPerturbedPoses) {
  std::mt19937 rng(7);
  const BundleProblem truth = Synthetic(rng);
  BundleProblem problem = truth;
  std::normal_distribution<double> noise(0, 1);
  for (int c = 1; c < 3; ++c) {
    problem.poses[c].rotation += Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) * 0.03;
    problem.poses[c].translation += Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) * 0.1;
  }
  for (int c = 1; c < 3; ++c) EXPECT_GT(RotationErrorDegrees(problem.poses[c], truth.poses[c]), 0.5);
  BundleOptions options;
  options.refine_points = false;  // known points fix the gauge: poses are recovered exactly
  const BundleReport report = RefineBundle(&problem, options);
  for (int c = 1; c < 3; ++c) {
    EXPECT_GT(report.rms_before[c], 5.0);
    EXPECT_LT(report.rms_after[c], 1e-4);
    EXPECT_LT(RotationErrorDegrees(problem.poses[c], truth.poses[c]), 1e-4);
    EXPECT_LT((problem.poses[c].translation - truth.poses[c].translation).norm(), 1e-5);
    EXPECT_NEAR(problem.intrinsics[c].f, truth.intrinsics[c].f, 1e-3);
  }
}

// The principal point is held unless asked for: a start 4 px off stays there (the rest absorbs
// what it can), and with refine_principal_point the truth comes back.
TEST(BundleRefinement, PrincipalPointIsHeldUnlessRequested) {
  std::mt19937 rng(9);
  const BundleProblem truth = Synthetic(rng);
  BundleProblem held = truth;
  held.intrinsics[1].cx += 4;
  held.intrinsics[1].cy -= 3;
  BundleProblem refined = held;
  BundleOptions options;
  options.refine_points = false;
  RefineBundle(&held, options);
  EXPECT_EQ(held.intrinsics[1].cx, truth.intrinsics[1].cx + 4);
  EXPECT_EQ(held.intrinsics[1].cy, truth.intrinsics[1].cy - 3);
  options.refine_principal_point = true;
  const BundleReport report = RefineBundle(&refined, options);
  EXPECT_NEAR(refined.intrinsics[1].cx, truth.intrinsics[1].cx, 1e-3);
  EXPECT_NEAR(refined.intrinsics[1].cy, truth.intrinsics[1].cy, 1e-3);
  EXPECT_LT(report.rms_after[1], 1e-4);
}

TEST(BundleRefinement, RobustLossIgnoresOutliersAndRefinesPoints) {
  std::mt19937 rng(8);
  const BundleProblem truth = Synthetic(rng);
  BundleProblem problem = truth;
  std::normal_distribution<double> noise(0, 1);
  for (auto& o : problem.observations) o.pixel += Eigen::Vector2d(noise(rng), noise(rng)) * 0.3;
  for (int i = 0; i < 10; ++i) problem.observations[i * 13].pixel += Eigen::Vector2d(40, -30);
  for (auto& p : problem.points) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) * 0.01;
  problem.poses[2].rotation += Eigen::Vector3d(0.02, -0.01, 0.01);
  BundleProblem plain = problem;
  // Free points leave a similarity gauge; known intrinsics keep rotations comparable with truth
  // (free focal lengths trade off against depth and rotation on three views).
  BundleOptions robust;
  robust.refine_intrinsics = false;
  const BundleReport report = RefineBundle(&problem, robust);
  BundleOptions l2 = robust;
  l2.huber_pixels = 1e6;  // effectively squared loss
  RefineBundle(&plain, l2);
  // 0.3 px noise on three views and one held point: well under a degree, from 1.4 degrees off.
  EXPECT_LT(RotationErrorDegrees(problem.poses[2], truth.poses[2]), 0.5);
  EXPECT_LT(RotationErrorDegrees(problem.poses[2], truth.poses[2]),
            RotationErrorDegrees(plain.poses[2], truth.poses[2]));
  EXPECT_LT(report.rms_after[2], report.rms_before[2]);
}

TEST(BundleRefinement, BadIndicesAreErrors) {
  BundleProblem problem;
  EXPECT_NE(testing::ErrorOf([&] { RefineBundle(&problem); }).find("no observations"), std::string::npos);
  problem.poses.resize(1);
  problem.intrinsics.resize(1);
  problem.observations.push_back({0, 0, 3, Eigen::Vector2d::Zero()});
  EXPECT_NE(testing::ErrorOf([&] { RefineBundle(&problem); }).find("not there"), std::string::npos);
}

}  // namespace
}  // namespace hdr4d
