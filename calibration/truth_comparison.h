// How close a calibration came to the truth of a synthetic capture (`hdr4d datagen --capture`
// writes it in truth/: cameras.json, response.csv, the rendered EXRs): `hdr4d calibrate --truth`.
//   geometry:   the calibrated camera centres aligned to the true ones by a similarity (Umeyama:
//               scale, rotation, translation, least squares), then per camera the rotation error
//               in degrees and the position error relative to the rig's size; focal length and
//               principal point against the truth
//   response:   the recovered inverse response against the true one, both x(128) = 1, over the
//               codes 16..240
//   HDR:        every fused frame against its rendered EXR (through the true lens and calibrate's
//               undistortion where either resampled it) after one scale per colour channel
//               (a calibration knows radiance only up to scale), over the pixels whose radiance
//               the brackets measure (truth/cameras.json's measured_radiance)
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hdr4d {

struct Similarity {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return scale * rotation * p + translation; }
};

// The similarity that maps `from` onto `to` in the least-squares sense (Umeyama 1991). Throws
// hdr4d::Error for fewer than 3 points, unequal counts, or points (nearly) on one line, where the
// rotation about that line is not determined.
Similarity AlignSimilarity(const std::vector<Eigen::Vector3d>& from,
                           const std::vector<Eigen::Vector3d>& to);

// The angle in degrees of the rotation between two rotation matrices.
double RotationAngleDegrees(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

// The rotation A that minimises sum_i ||A from_i - to_i||_F (chordal L2 mean; SVD projection of
// sum to_i from_i^T onto SO(3)). Throws hdr4d::Error for unequal counts or none.
Eigen::Matrix3d AlignOrientations(const std::vector<Eigen::Matrix3d>& from,
                                  const std::vector<Eigen::Matrix3d>& to);

struct CameraTruthError {
  std::string name;
  bool geometry = false;
  double rotation_deg = 0;      // after the similarity fitted to the centres
  double rotation_oriented_deg = 0;  // after the rotation fitted to the orientations
  double position_error = 0;    // after the similarity, in the truth's units
  double position_relative = 0; // position_error / rig size
  double focal = 0, focal_truth = 0, focal_relative = 0;  // pixels; |f - f_true| / f_true
  double principal_point_px = 0;  // |(cx, cy) - truth|
  bool hdr = false;
  double hdr_median_relative = 0;  // median over its values of |s c - truth| / truth
  long hdr_values = 0;
  std::array<double, 3> hdr_scale{1, 1, 1};  // median of s c / truth per channel (1 = agrees)
  double vignetting_truth = 0;  // the capture's falloff v (calibration.json has the estimate)
};

struct TruthComparison {
  std::vector<CameraTruthError> cameras;
  bool geometry = false;
  Similarity alignment;            // calibrated world -> truth world
  double rig_size = 0;             // RMS distance of the true centres from their centroid
  double max_rotation_deg = 0, mean_rotation_deg = 0;  // after the centres' similarity
  // The same after the rotation that best maps the calibrated orientations onto the true ones
  // (gauge-free: the centres' errors do not tilt it).
  double max_rotation_oriented_deg = 0;
  // Max over camera pairs of the angle between calibrated and true relative rotation
  // R_i^T R_j (no alignment at all).
  double max_relative_rotation_deg = 0;
  // Angle between the centres' similarity rotation and the orientations' rotation: how much
  // the centre errors tilt the similarity (a rig of few, nearly coplanar cameras amplifies them).
  double alignment_tilt_deg = 0;
  double max_position_relative = 0, mean_position_relative = 0;
  double max_focal_relative = 0;
  bool response = false;
  std::array<double, 3> response_max_relative{};  // max over codes 16..240 of |x/x_true - 1|
  std::array<double, 3> response_rms_relative{};
  bool hdr = false;
  std::array<double, 3> hdr_scale{};  // truth = scale x calibrated, per channel (median ratio)
  double hdr_median_relative = 0, hdr_p90_relative = 0, hdr_within_10_percent = 0;
  long hdr_values = 0;             // channel values compared
  double hdr_excluded_fraction = 0;  // pixels outside the measured radiance range
  // Slope of log calibrated against log true radiance (1: no compression or stretch). The
  // reference is the render as the calibrated camera delivers it: through the capture's true lens
  // and calibrate's own undistortion (both bilinear resamplings, which blur the texture), so that a
  // perfect calibration reads 1; hdr_loglog_slope_render is against the render itself, and
  // hdr_loglog_slope_render_floor what a perfect calibration reads there (the resampling alone).
  double hdr_loglog_slope = 0, hdr_loglog_slope_render = 0, hdr_loglog_slope_render_floor = 0;
  int hdr_resampled_frames = 0;  // frames whose reference was resampled (a lens or undistortion)
  // Median relative error over the darkest fifth of the measured values (the shadows).
  double hdr_dark_median_relative = 0;
  // The cameras' disagreement against the truth: max over cameras and channels of
  // |hdr_scale / the cameras' median - 1| (after calibrate's gains; 0 = they agree).
  double hdr_camera_disagreement = 0;
  int hdr_frames = 0;
  std::vector<std::string> notes;  // what was not compared and why
};

// `calibrated`: calibrate's --out (rig.json, response.csv, hdr/<camera>/<frame>.exr, whichever
// exist); `truth`: datagen --capture's truth/. Throws hdr4d::Error naming the file for a
// missing or malformed truth/cameras.json, a calibrated camera or frame the truth lacks, or
// images of different sizes.
TruthComparison CompareWithTruth(const std::filesystem::path& calibrated,
                                 const std::filesystem::path& truth);

nlohmann::json TruthComparisonJson(const TruthComparison& comparison);
// A Markdown table per camera and a summary line per part.
std::string TruthComparisonMarkdown(const TruthComparison& comparison);

}  // namespace hdr4d
