// Focal restarts of the rig refinement (issue 54): the robust cost, the re-triangulation, and
// that the start of least cost is the one kept and every start is reported.
#include "calibration/focal_multistart.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "calibration/synthetic_rig_test_util.h"
#include "core/util/error.h"

namespace hdr4d {
namespace {

constexpr double kF = 500, kCx = 320, kCy = 240;

BundlePose PoseOf(const Eigen::Isometry3d& cam_from_world) {
  const Eigen::AngleAxisd aa(cam_from_world.linear());
  return {aa.angle() * aa.axis(), cam_from_world.translation(), false};
}

// Four cameras on an arc around points in a 3-unit cube, one intrinsics block each (truth kF),
// pixels with `noise` px; `outliers` of the observations moved by 5-20 px.
BundleProblem MakeRig(double noise, double outliers, unsigned seed = 3) {
  BundleProblem problem;
  for (int c = 0; c < 4; ++c) {
    problem.poses.push_back(PoseOf(CameraOnArc((c - 1.5) * 0.35, 4, 0.2 * c)));
    problem.intrinsics.push_back({kF, kCx, kCy, 0, 0});
    problem.intrinsics.back().hold_distortion = true;
  }
  problem.poses[0].fixed = true;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5), unit(0, 1), jump(5, 20);
  std::normal_distribution<double> n(0, noise);
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    const int point = static_cast<int>(problem.points.size());
    problem.points.push_back(x);
    for (int c = 0; c < 4; ++c) {
      Eigen::Vector2d pixel = ProjectRadial(problem.poses[c], problem.intrinsics[c], x);
      pixel += Eigen::Vector2d(n(rng), n(rng));
      if (unit(rng) < outliers) pixel.x() += jump(rng);
      problem.observations.push_back({c, c, point, pixel});
    }
  }
  return problem;
}

TEST(FocalMultistart, RobustCostIsTheHuberCost) {
  BundleProblem problem = MakeRig(0, 0);
  EXPECT_NEAR(RobustCost(problem, 1.0), 0, 1e-12);
  problem.observations.resize(2);
  problem.observations[0].pixel.x() += 0.5;  // quadratic: 1/2 0.25
  problem.observations[1].pixel.y() += 3.0;  // linear: 1/2 (2 * 3 - 1)
  EXPECT_NEAR(RobustCost(problem, 1.0), 0.125 + 2.5, 1e-9);
  // The refinement lowers it (it is the quantity Ceres minimises).
  BundleProblem noisy = MakeRig(0.7, 0.05);
  const double before = RobustCost(noisy, 1.0);
  RefineBundle(&noisy);
  EXPECT_LT(RobustCost(noisy, 1.0), before);
}

TEST(FocalMultistart, RetriangulateRecoversPointsUnderTheCameras) {
  const BundleProblem truth = MakeRig(0, 0);
  BundleProblem moved = truth;
  for (Eigen::Vector3d& p : moved.points) p += Eigen::Vector3d(0.3, -0.2, 0.5);
  Retriangulate(&moved);
  for (std::size_t i = 0; i < truth.points.size(); ++i)
    ASSERT_LT((moved.points[i] - truth.points[i]).norm(), 1e-8) << i;
}

TEST(FocalMultistart, KeepsTheStartOfLeastCostAndReportsAll) {
  BundleProblem problem = MakeRig(0.7, 0.05);
  for (BundleIntrinsics& k : problem.intrinsics) k.f *= 1.03;  // COLMAP's focal 3% long
  const std::vector<double> scales = {0.96, 0.98, 1.0, 1.02};
  BundleReport report;
  const FocalStartReport starts = RefineFromFocalStarts(&problem, {0, 1, 2, 3}, scales, {}, &report);
  ASSERT_EQ(starts.starts.size(), scales.size());
  double least = 1e300;
  for (std::size_t i = 0; i < scales.size(); ++i) {
    EXPECT_EQ(starts.starts[i].scale, scales[i]);
    least = std::min(least, starts.starts[i].cost);
  }
  ASSERT_GE(starts.kept, 0);
  EXPECT_EQ(starts.starts[starts.kept].cost, least);
  // The problem is the kept start's solution.
  EXPECT_NEAR(RobustCost(problem, 1.0), least, 1e-9 * least);
  EXPECT_NEAR(problem.intrinsics[0].f, starts.starts[starts.kept].focal, 1e-9);
  EXPECT_EQ(report.rms_before.size(), problem.poses.size());
  EXPECT_GT(report.iterations, 0);
}

// The stall: COLMAP's focal lengths 3% short, points triangulated under them. One refinement
// ends 1.2% short (Ceres reports convergence after ~11 iterations) at a cost 5% above the
// refinement's from the truth. The restarts from x0.96..x1.04 end as low as that. (Seed 3 of MakeRig shows it most; seed 4 ends
// 0.4% short from the same start.)
TEST(FocalMultistart, RestartsLeaveTheMinimumNearTheWrongStart) {
  BundleProblem colmap = MakeRig(0.7, 0, 3);
  for (BundleIntrinsics& k : colmap.intrinsics) k.f *= 0.97;
  Retriangulate(&colmap);
  BundleProblem once = colmap, restarted = colmap;
  BundleReport report;
  RefineFromFocalStarts(&once, {0, 1, 2, 3}, {1.0}, {}, &report);
  const FocalStartReport starts = RefineFromFocalStarts(&restarted, {0, 1, 2, 3}, DefaultFocalStarts(), {}, &report);
  BundleProblem from_truth = MakeRig(0.7, 0, 3);
  RefineBundle(&from_truth);
  auto mean_error = [](const BundleProblem& p) {
    double sum = 0;
    for (const BundleIntrinsics& k : p.intrinsics) sum += k.f / kF - 1;
    return std::abs(sum / static_cast<double>(p.intrinsics.size()));
  };
  EXPECT_GT(mean_error(once), 0.01);
  EXPECT_LT(mean_error(restarted), 0.01);
  // Measured: focal 1.22% / 0.86% / 0.21% off (mean over cameras), cost 349.3 / 331.7 / 332.3.
  EXPECT_GT(RobustCost(once, 1.0), RobustCost(from_truth, 1.0) * 1.03);  // a worse minimum
  EXPECT_LE(RobustCost(restarted, 1.0), RobustCost(from_truth, 1.0) * 1.001);
  EXPECT_GT(starts.starts[starts.kept].scale, 1.0);  // the winner started above COLMAP's focal
}

TEST(FocalMultistart, NoScalesIsAnError) {
  BundleProblem problem = MakeRig(0.5, 0);
  BundleReport report;
  EXPECT_THROW(RefineFromFocalStarts(&problem, {0}, {}, {}, &report), Error);
}

}  // namespace
}  // namespace hdr4d
