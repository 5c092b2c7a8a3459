#include "calibration/bundle_refinement.h"

#include <ceres/ceres.h>
#include <Eigen/Geometry>
#include <ceres/manifold.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/util/error.h"

namespace hdr4d {
namespace {

// Residual of one observation: projected minus observed pixel (COLMAP's RADIAL model). The
// focal length is a block of its own so that cameras of one model can share it; `k` is cx, cy,
// k1, k2.
struct ReprojectionError {
  Eigen::Vector2d observed;

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* f, const T* k, const T* point, T* r) const {
    T p[3];
    ceres::AngleAxisRotatePoint(rotation, point, p);
    for (int i = 0; i < 3; ++i) p[i] += translation[i];
    // A point behind (or on) the camera plane cannot be seen: a large, smooth penalty instead of
    // a division by zero.
    if (p[2] <= T(1e-9)) {
      r[0] = r[1] = T(1e3);
      return true;
    }
    const T x = p[0] / p[2], y = p[1] / p[2];
    const T r2 = x * x + y * y;
    const T d = T(1) + k[2] * r2 + k[3] * r2 * r2;
    r[0] = f[0] * d * x + k[0] - T(observed.x());
    r[1] = f[0] * d * y + k[1] - T(observed.y());
    return true;
  }
};

double* Rest(BundleIntrinsics& k) { return &k.cx; }  // cx, cy, k1, k2 are contiguous

// Holds what the options and the intrinsics say is not refined.
void ConfigureIntrinsics(const BundleOptions& options, double* focal, BundleIntrinsics& k, ceres::Problem* problem) {
  if (!problem->HasParameterBlock(Rest(k))) return;
  if (!options.refine_intrinsics || k.fixed) {
    problem->SetParameterBlockConstant(focal);
    problem->SetParameterBlockConstant(Rest(k));
    return;
  }
  std::vector<int> held;  // of cx, cy, k1, k2
  if (!options.refine_principal_point) held.insert(held.end(), {0, 1});
  if (k.hold_distortion) {
    held.insert(held.end(), {2, 3});
  } else if (k.hold_k2) {
    held.push_back(3);
  }
  if (held.size() == 4) {
    problem->SetParameterBlockConstant(Rest(k));
  } else if (!held.empty()) {
    problem->SetManifold(Rest(k), new ceres::SubsetManifold(4, held));
  }
}

std::vector<double> RmsPerPose(const BundleProblem& problem, std::vector<int>* counts) {
  std::vector<double> sum(problem.poses.size(), 0.0);
  std::vector<int> n(problem.poses.size(), 0);
  for (const BundleObservation& o : problem.observations) {
    const Eigen::Vector2d e = ProjectRadial(problem.poses[o.pose], problem.intrinsics[o.intrinsics],
                                            problem.points[o.point]) - o.pixel;
    sum[o.pose] += e.squaredNorm();
    ++n[o.pose];
  }
  std::vector<double> rms(sum.size(), 0.0);
  for (std::size_t i = 0; i < sum.size(); ++i) rms[i] = n[i] > 0 ? std::sqrt(sum[i] / n[i]) : 0.0;
  if (counts) *counts = n;
  return rms;
}

}  // namespace

Eigen::Vector2d ProjectRadial(const BundlePose& pose, const BundleIntrinsics& k, const Eigen::Vector3d& point) {
  double p[3];
  ceres::AngleAxisRotatePoint(pose.rotation.data(), point.data(), p);
  for (int i = 0; i < 3; ++i) p[i] += pose.translation[i];
  if (p[2] <= 1e-12) return {std::nan(""), std::nan("")};
  const double x = p[0] / p[2], y = p[1] / p[2], r2 = x * x + y * y;
  const double d = 1 + k.k1 * r2 + k.k2 * r2 * r2;
  return {k.f * d * x + k.cx, k.f * d * y + k.cy};
}

Eigen::Matrix3d RotationOf(const BundlePose& pose) {
  const double angle = pose.rotation.norm();
  return angle > 0 ? Eigen::AngleAxisd(angle, pose.rotation / angle).toRotationMatrix()
                   : Eigen::Matrix3d::Identity();
}

Eigen::Vector2d NormalisedRadial(const BundleIntrinsics& k, const Eigen::Vector2d& pixel) {
  const Eigen::Vector2d distorted = (pixel - Eigen::Vector2d(k.cx, k.cy)) / k.f;
  Eigen::Vector2d x = distorted;
  for (int i = 0; i < 20; ++i) {
    const double r2 = x.squaredNorm();
    x = distorted / (1 + k.k1 * r2 + k.k2 * r2 * r2);
  }
  return x;
}

BundleReport RefineBundle(BundleProblem* problem, const BundleOptions& options) {
  if (problem->observations.empty()) Fail("bundle refinement: no observations");
  for (const BundleObservation& o : problem->observations)
    if (o.pose < 0 || o.pose >= static_cast<int>(problem->poses.size()) || o.intrinsics < 0 ||
        o.intrinsics >= static_cast<int>(problem->intrinsics.size()) || o.point < 0 ||
        o.point >= static_cast<int>(problem->points.size()))
      Fail("bundle refinement: an observation names a pose, intrinsics or point that is not there");
  BundleReport report;
  report.rms_before = RmsPerPose(*problem, &report.observations);

  ceres::Problem ceres_problem;
  // One focal length per group, starting from the group's mean (std::map: stable addresses).
  std::map<int, double> group_focal;
  std::map<int, int> group_size;
  for (const BundleIntrinsics& k : problem->intrinsics)
    if (k.focal_group >= 0) group_focal[k.focal_group] += k.f, ++group_size[k.focal_group];
  for (auto& [g, f] : group_focal) f /= group_size[g];
  auto focal_of = [&](BundleIntrinsics& k) { return k.focal_group >= 0 ? &group_focal[k.focal_group] : &k.f; };
  for (BundleObservation& o : problem->observations) {
    auto* cost = new ceres::AutoDiffCostFunction<ReprojectionError, 2, 3, 3, 1, 4, 3>(new ReprojectionError{o.pixel});
    BundlePose& pose = problem->poses[o.pose];
    BundleIntrinsics& k = problem->intrinsics[o.intrinsics];
    ceres_problem.AddResidualBlock(cost, new ceres::HuberLoss(options.huber_pixels), pose.rotation.data(),
                                   pose.translation.data(), focal_of(k), Rest(k), problem->points[o.point].data());
  }
  for (BundlePose& pose : problem->poses) {
    if (!pose.fixed || !ceres_problem.HasParameterBlock(pose.rotation.data())) continue;
    ceres_problem.SetParameterBlockConstant(pose.rotation.data());
    ceres_problem.SetParameterBlockConstant(pose.translation.data());
  }
  for (BundleIntrinsics& k : problem->intrinsics) ConfigureIntrinsics(options, focal_of(k), k, &ceres_problem);
  for (Eigen::Vector3d& p : problem->points)
    if (!options.refine_points && ceres_problem.HasParameterBlock(p.data()))
      ceres_problem.SetParameterBlockConstant(p.data());
  if (options.refine_points) {
    // A fixed pose leaves the scale free (a rank-deficient system); also holding the point that
    // the fixed camera sees most often pins the scale through its depth.
    std::vector<int> seen(problem->points.size(), 0);
    for (const BundleObservation& o : problem->observations)
      if (problem->poses[o.pose].fixed) seen[o.point] += 1;
    std::vector<int> track(problem->points.size(), 0);
    for (const BundleObservation& o : problem->observations) track[o.point] += seen[o.point] > 0;
    const auto best = std::max_element(track.begin(), track.end());
    if (best != track.end() && *best > 0)
      ceres_problem.SetParameterBlockConstant(problem->points[best - track.begin()].data());
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 2;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &ceres_problem, &summary);
  report.iterations = static_cast<int>(summary.iterations.size());
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  for (BundleIntrinsics& k : problem->intrinsics)
    if (k.focal_group >= 0) k.f = group_focal[k.focal_group];
  report.rms_after = RmsPerPose(*problem, nullptr);
  return report;
}

}  // namespace hdr4d
