// The geometry of a fixed rig from a COLMAP sparse model: one pose and one set of intrinsics
// per physical camera (its static images share them), refined with Ceres, the scene centred and
// scaled for the trainer, and the points kept for point3d.ply. Saved as rig.json so that
// `--stage radiometry` can build the dataset later.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calibration/bundle_refinement.h"
#include "calibration/focal_multistart.h"
#include "calibration/rig_time_points.h"
#include "core/geometry/colmap_model.h"
#include "core/geometry/ply.h"

namespace hdr4d {

struct RigCamera {
  std::string name;
  int width = 0, height = 0;
  BundleIntrinsics intrinsics;
  Eigen::Matrix4d world_from_cam_gl = Eigen::Matrix4d::Identity();  // normalised world
  double rms_before = 0, rms_after = 0;  // reprojection error, pixels, before/after refinement
  int observations = 0;
  int static_images_registered = 0;
  double max_distortion_pixels = 0;
  bool undistort = false;  // distortion above the threshold: images are undistorted
  bool board_intrinsics = false;  // intrinsics from a calibration board
  // Model selection: did k1, k2 explain the observations beyond noise (else held at 0)?
  bool distortion_kept = true;
  int distortion_terms = 2;     // radial terms kept: 0 (none), 1 (k1), 2 (k1, k2)
  // BIC of no distortion minus BIC of the model kept (> 0: a term was kept); BIC = N ln(SSE / N)
  // + p ln N over the N = 2 x observations residual components, p the radial terms.
  double distortion_score = 0;
  // One focal length with the other rig cameras of its image size (they look like one model:
  // BIC prefers one focal length to one each; or --shared-intrinsics).
  bool focal_shared = false;
};

struct Rig {
  std::vector<RigCamera> cameras;
  PointCloud points;                         // normalised world
  std::vector<std::vector<int>> visibility;  // rig cameras that saw each point (not in rig.json)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // COLMAP world point moved to the origin
  double scale = 1;                          // then multiplied by this
  int extra_images_registered = 0;
  int refinement_iterations = 0;
  std::string model_source;  // where the sparse model came from
  std::string intrinsics_source = "COLMAP, refined with Ceres";
  double metres_per_unit = 0;  // of the normalised world; 0 = unknown (no board seen by 2 cameras)
  std::vector<std::string> notes;  // what the report must say (not in rig.json)
  // The points of the rig's own sequence times added to the refinement (absent: not asked for).
  // They constrain the geometry only: point3d.ply and the normalisation stay COLMAP's points.
  std::optional<RigTimeReport> rig_time;
  // The focal restarts of the first refinement and the one kept (absent: one start, COLMAP's).
  std::optional<FocalStartReport> focal_starts;

  const RigCamera* Find(const std::string& name) const;
};

struct RigOptions {
  // Intrinsics known from a calibration board, by camera name: used as they are.
  std::map<std::string, BundleIntrinsics> board_intrinsics;
  double undistort_threshold_pixels = 0.5;
  bool show_progress = true;
  // One focal length and distortion for every rig camera of the same image size (cameras of
  // one model); off: each camera its own.
  bool shared_intrinsics = false;
  // Keep k1, k2 of a camera only where they lower the reprojection error by more than their
  // two degrees of freedom explain (BIC); off: always keep COLMAP's distortion.
  bool select_distortion = true;
  // Rig cameras of one image size share one focal length where that explains the observations
  // as well as one each (BIC over their residuals, C - 1 fewer parameters): a focal length error
  // of one camera moves its centre along its axis (a rig camera is seen in one pose), and cameras
  // of one model have one focal length. Off: each camera its own.
  bool select_shared_focal = true;
  // Off: COLMAP's poses, intrinsics and points as they are, no Ceres refinement and no model
  // selection (a diagnosis: what the refinement changes).
  bool refine = true;
  // Features of the rig's sequence times (rig_time_points.h): their points join COLMAP's before
  // the refinement and the model selections. Empty: COLMAP's points only.
  std::vector<RigTimeFeatures> rig_times;
  RigTimeOptions rig_time;
  // The first refinement restarts from these scalings of the free rig cameras' focal lengths and
  // keeps the least robust cost (focal_multistart.h); include 1 (COLMAP's own start). Empty:
  // one start, COLMAP's.
  std::vector<double> focal_starts;
};

// Builds the rig for `camera_names` from `model`, whose image names are <camera>/<file> (any
// other folder counts as extra images, used for the points and dropped). Throws hdr4d::Error
// naming the camera when none of its static images was registered.
Rig RigFromColmap(const ColmapModel& model,
                  const std::vector<std::string>& camera_names,
                  const RigOptions& options = {});

void WriteRigJson(const std::filesystem::path& path, const Rig& rig);
// Throws hdr4d::Error naming the file and key.
Rig ReadRigJson(const std::filesystem::path& path);

}  // namespace hdr4d
