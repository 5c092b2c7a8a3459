// Points from the rig's own sequence (issue 54): COLMAP's model holds one image per rig camera
// (static/), but the fixed cameras also see every time of the sequence together, static scene
// and moving actors alike. Per time: SIFT on one mid bracket per rig camera, matches only between
// rig cameras of that time (ratio test and cross-check), kept where the Sampson distance under
// the current poses and intrinsics is small; matches joined into tracks and triangulated (DLT) on
// the fixed poses, with cheirality, reprojection and triangulation-angle checks. The points join
// the bundle problem of RigFromColmap on the rig cameras' existing poses (no new poses), so that
// the refinement and the model selections of focal length and distortion see many more
// observations. A track that lands on an existing point (COLMAP's, or one of an earlier time:
// the static scene is seen again at every time) extends that point instead of repeating it.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "calibration/bundle_refinement.h"
#include "calibration/capture.h"

namespace hdr4d {

struct ViewFeatures {
  std::vector<Eigen::Vector2d> pixels;  // COLMAP's convention: (0.5, 0.5) is the first pixel's centre
  cv::Mat descriptors;                  // CV_32F, one row per pixel
};

struct RigTimeFeatures {
  std::string label;                // "frame 3": what the report names
  std::vector<ViewFeatures> views;  // by rig camera (no pixels: that camera has no image)
};

struct RigTimeOptions {
  double ratio = 0.8;                  // Lowe's ratio test, both directions
  double max_sampson_pixels = 2;       // a match farther from the epipolar geometry is dropped
  double max_reprojection_pixels = 2;  // every observation of a triangulated point
  double min_angle_degrees = 1.5;      // the widest angle between a point's rays (COLMAP's mapper: 1.5)
  double same_point_pixels = 1;        // an observation this close to an existing one: the same point
};

struct RigTimeReport {
  int times = 0, times_used = 0;
  int matches = 0;          // cross-checked ratio-test matches between rig cameras of one time
  int matches_kept = 0;     // of those, under the Sampson bound
  int tracks = 0;           // joined matches, one keypoint per camera at most
  int rejected_cheirality = 0, rejected_reprojection = 0, rejected_angle = 0;
  int points_added = 0, observations_added = 0;
  int points_extended = 0;  // existing points that gained observations in more cameras
  int repeats = 0;          // observations dropped as an existing point's again
  double rms_before = 0;    // px, the added observations at triangulation (current poses)
  double rms_after = 0;     // px, the same observations after the refinement (set by the caller)
  std::vector<std::string> notes;  // times skipped and why
};

// SIFT (OpenCV's, on the upsampled image as COLMAP's) of a grey version of `image`, as RootSIFT
// descriptors. Throws hdr4d::Error naming the file when it cannot be read.
ViewFeatures ExtractSift(const std::filesystem::path& image, int max_features = 8000);

// One mid bracket per rig camera (`camera_names` order) per frame of the capture's sequence.
std::vector<RigTimeFeatures> ExtractRigTimes(const Capture& capture, const std::vector<std::string>& camera_names,
                                             bool show_progress);

// Adds the points of every time to `problem`, whose first rig_intrinsics.size() poses are the rig
// cameras (pose c with intrinsics rig_intrinsics[c]). A time without a kept match is skipped
// and named in the notes.
RigTimeReport AddRigTimePoints(const std::vector<RigTimeFeatures>& times, const std::vector<int>& rig_intrinsics,
                               BundleProblem* problem, const RigTimeOptions& options = {});

// RMS (px) of problem.observations[first..]: the added observations' reprojection error.
double ObservationRms(const BundleProblem& problem, std::size_t first);

}  // namespace hdr4d
