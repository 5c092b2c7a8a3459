// `hdr4d calibrate`: a capture (calibration/capture.h) in, a dataset (ARCHITECTURE §3) out.
//   geometry:   COLMAP on static/ (or --colmap-model), Ceres rig refinement, normalisation,
//               rig.json, point3d.ply
//   radiometry: Debevec-Malik response from the brackets, HDR fusion of every frame with
//               motion fallback, images/ (undistorted when needed), hdr/, response.csv/.png
//   dataset:    transforms_{train,test}.json once both the rig and the images exist
//   report:     report.md (+ calibration.json with the same numbers)
// Everything is written into a staging folder beside --out and moved in only when every
// stage succeeded, so a failure leaves --out as it was.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "calibration/camera_gains.h"
#include "calibration/hdr_fusion.h"
#include "calibration/response_recovery.h"

namespace hdr4d {

enum class CalibrationStage { kGeometry, kRadiometry, kAll };
CalibrationStage ParseCalibrationStage(const std::string& name);  // geometry|radiometry|all

struct CalibrateOptions {
  std::filesystem::path capture, out;
  std::optional<std::filesystem::path> colmap_model;  // reuse this sparse model
  CalibrationStage stage = CalibrationStage::kAll;
  std::string board;  // "<cols>x<rows>:<square metres>": a checkerboard in static/ (optional)
  std::string colmap_binary = "colmap";
  int colmap_max_image_size = 0;  // COLMAP's SIFT downscales larger images to this; 0 = its default
  double fps = 30;                // frame index / fps = time (seconds)
  std::string test_camera;        // held-out camera; empty = the last one (when >= 2 cameras)
  ResponseOptions response;
  FusionOptions fusion;
  double undistort_threshold_pixels = 0.5;
  bool shared_intrinsics = false;  // rig cameras of one image size share focal and distortion
  bool select_distortion = true;   // keep k1, k2 only where the data shows them (BIC)
  bool select_shared_focal = true;  // one focal length for alike cameras where BIC says so
  bool refine_rig = true;          // false: COLMAP's model as it is (a diagnosis)
  // Points from the rig cameras' own sequence times join the refinement (rig_time_points.h).
  bool rig_time_points = false;
  // The rig refinement restarts from several focal lengths once the models are chosen
  // (focal_multistart.h, rig_geometry.cpp).
  bool focal_multistart = true;
  bool per_camera_response = false;  // each camera its own curve even when they look alike
  bool correct_gains = true;  // divide each camera's HDR by its gains (calibration/camera_gains.h)
  // The surface patch the gains compare, in pixels of the camera that sees it smallest (0: a
  // 3x3 window in every camera, as before).
  double gain_footprint_pixels = kGainFootprintPixels;
  // Which cameras' vignetting is divided out of their HDR and brackets (vignetting_correction.h).
  VignettingCorrection vignetting = VignettingCorrection::kAuto;
  bool show_progress = true;
};

struct CalibrateSummary {
  int cameras = 0, frames = 0, images_written = 0;
  bool dataset_written = false;
  double seconds_geometry = 0, seconds_radiometry = 0;
};

CalibrateSummary Calibrate(const CalibrateOptions& options);

}  // namespace hdr4d
