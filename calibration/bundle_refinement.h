// Ceres refinement of a fixed rig: one pose per physical camera (every static image a camera
// took shares it, as the rig does not move), intrinsics per camera (one focal length and
// radial k1 k2 as COLMAP's RADIAL model; the principal point only on request), the 3D points,
// and a robust (Huber) loss so that COLMAP's remaining outliers do not pull the poses.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hdr4d {

struct BundlePose {
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // cam_from_world, angle-axis (OpenCV axes)
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  bool fixed = false;  // the gauge: one camera is held
};

struct BundleIntrinsics {
  double f = 1, cx = 0, cy = 0, k1 = 0, k2 = 0;  // contiguous: Ceres sees them as one block
  bool fixed = false;  // known from elsewhere (a calibration board): not refined
  bool hold_distortion = false;  // k1, k2 kept as they are (0: a distortion-free lens)
  bool hold_k2 = false;          // k2 alone kept as it is (a one-term radial model)
  // Intrinsics of one group (>= 0) share one focal length (cameras of one model); each keeps its
  // own principal point and distortion. -1: its own focal length.
  int focal_group = -1;
};

struct BundleObservation {
  int pose = 0, intrinsics = 0, point = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
};

struct BundleProblem {
  std::vector<BundlePose> poses;
  std::vector<BundleIntrinsics> intrinsics;
  std::vector<Eigen::Vector3d> points;
  std::vector<BundleObservation> observations;
};

struct BundleOptions {
  bool refine_points = true;
  bool refine_intrinsics = true;
  // The principal point with the focal length and distortion. Off by default, as in COLMAP's
  // bundle adjustment: a rig camera is seen in one pose, where a principal point shift and a
  // small turn of the camera explain the points almost equally well, so refining both lets the
  // pair drift (a datagen rig moved its principal points by up to 80 px and its rotations by up
  // to 12 degrees at an unchanged reprojection error).
  bool refine_principal_point = false;
  double huber_pixels = 1.0;  // residuals beyond this grow linearly
  int max_iterations = 100;
};

struct BundleReport {
  std::vector<double> rms_before, rms_after;  // per pose, pixels (0 observations: 0)
  std::vector<int> observations;              // per pose
  int iterations = 0;
  bool converged = false;
};

// The pixel where `point` (world) lands in a camera, with radial distortion.
Eigen::Vector2d ProjectRadial(const BundlePose& pose, const BundleIntrinsics& k, const Eigen::Vector3d& point);

// The rotation (cam_from_world) of a pose.
Eigen::Matrix3d RotationOf(const BundlePose& pose);

// The pinhole (normalised) coordinates of a pixel: the radial model inverted by fixed-point
// iteration (converges for the few-percent distortion of real lenses).
Eigen::Vector2d NormalisedRadial(const BundleIntrinsics& k, const Eigen::Vector2d& pixel);

// Refines `problem` in place. Throws hdr4d::Error for an index out of range or no observations.
BundleReport RefineBundle(BundleProblem* problem, const BundleOptions& options = {});

}  // namespace hdr4d
