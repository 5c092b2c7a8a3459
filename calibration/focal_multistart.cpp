#include "calibration/focal_multistart.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/error.h"

namespace hdr4d {

std::vector<double> DefaultFocalStarts() { return {0.96, 0.97, 0.98, 0.99, 1.0, 1.01, 1.02, 1.03, 1.04}; }

double RobustCost(const BundleProblem& problem, double huber_pixels) {
  const double a2 = huber_pixels * huber_pixels;
  double cost = 0;
  for (const BundleObservation& o : problem.observations) {
    const Eigen::Vector2d e = ProjectRadial(problem.poses[o.pose], problem.intrinsics[o.intrinsics],
                                            problem.points[o.point]) - o.pixel;
    // Behind the camera: the residual RefineBundle uses there, (1e3, 1e3).
    const double s = std::isfinite(e.squaredNorm()) ? e.squaredNorm() : 2e6;
    cost += 0.5 * (s <= a2 ? s : 2 * huber_pixels * std::sqrt(s) - a2);
  }
  return cost;
}

void Retriangulate(BundleProblem* problem) {
  const std::size_t n = problem->points.size();
  std::vector<Eigen::Matrix3d> a(n, Eigen::Matrix3d::Zero());
  std::vector<Eigen::Vector3d> b(n, Eigen::Vector3d::Zero());
  std::vector<int> rays(n, 0);
  for (const BundleObservation& o : problem->observations) {
    const BundlePose& pose = problem->poses[o.pose];
    const Eigen::Matrix3d world_from_cam = RotationOf(pose).transpose();
    const Eigen::Vector3d centre = -world_from_cam * pose.translation;
    const Eigen::Vector2d x = NormalisedRadial(problem->intrinsics[o.intrinsics], o.pixel);
    const Eigen::Vector3d d = (world_from_cam * Eigen::Vector3d(x.x(), x.y(), 1)).normalized();
    const Eigen::Matrix3d off_ray = Eigen::Matrix3d::Identity() - d * d.transpose();  // distance to the ray
    a[o.point] += off_ray, b[o.point] += off_ray * centre, ++rays[o.point];
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (rays[i] < 2) continue;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a[i]);  // ascending eigenvalues
    // Near-parallel rays: the meeting point is undetermined along them; keep the old point.
    if (eigen.eigenvalues()(0) < 1e-6 * eigen.eigenvalues()(2)) continue;
    problem->points[i] = a[i].ldlt().solve(b[i]);
  }
}

FocalStartReport RefineFromFocalStarts(BundleProblem* problem, const std::vector<int>& blocks,
                                       const std::vector<double>& scales, const BundleOptions& options,
                                       BundleReport* report) {
  if (scales.empty()) Fail("focal restarts: no starting scales");
  FocalStartReport starts;
  BundleProblem best;
  int iterations = 0;
  std::vector<double> rms_in;  // of the problem as it came in
  double best_cost = std::numeric_limits<double>::infinity();
  for (const double scale : scales) {
    BundleProblem trial = *problem;
    for (int block : blocks) trial.intrinsics[block].f *= scale;
    if (scale != 1.0) Retriangulate(&trial);
    BundleReport trial_report = RefineBundle(&trial, options);
    iterations += trial_report.iterations;
    if (scale == 1.0) rms_in = trial_report.rms_before;
    FocalStart s;
    s.scale = scale;
    s.focal = blocks.empty() ? 0 : trial.intrinsics[blocks.front()].f;
    s.cost = RobustCost(trial, options.huber_pixels);
    double sse = 0;
    int count = 0;
    for (std::size_t p = 0; p < trial_report.rms_after.size(); ++p)
      sse += trial_report.rms_after[p] * trial_report.rms_after[p] * trial_report.observations[p],
          count += trial_report.observations[p];
    s.rms = std::sqrt(sse / std::max(count, 1));
    starts.starts.push_back(s);
    // Strictly lower: on a tie the earlier start (in the fixed order) stays.
    if (s.cost < best_cost) {
      best_cost = s.cost;
      best = std::move(trial);
      starts.kept = static_cast<int>(starts.starts.size()) - 1;
      *report = trial_report;
    }
  }
  if (!rms_in.empty()) report->rms_before = rms_in;
  report->iterations = iterations;
  *problem = std::move(best);
  return starts;
}

}  // namespace hdr4d
