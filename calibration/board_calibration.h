// An optional checkerboard in the static images: intrinsics per camera from OpenCV
// (findChessboardCorners + calibrateCamera) and the metric scale of the scene from the board
// poses of two cameras that saw it at the same moment (same file name in both folders).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "calibration/bundle_refinement.h"

namespace hdr4d {

struct BoardSpec {
  int cols = 0, rows = 0;  // inner corners
  double square = 0;       // metres
};
// "<cols>x<rows>:<square metres>", e.g. "9x6:0.025". Throws hdr4d::Error for anything else.
BoardSpec ParseBoardSpec(const std::string& text);

struct BoardCalibration {
  int views = 0;  // images where the board was found
  BundleIntrinsics intrinsics;
  double rms = 0;  // OpenCV's reprojection RMS, pixels
  // world_from_cam for each image (by file name) in the board's frame, metres (OpenCV axes).
  std::map<std::string, Eigen::Matrix4d> board_from_cam;
};

// Detects the board in `images` (all width x height) and calibrates when it was found at least
// once (one view: principal point at the centre and one radial term). views = 0 otherwise.
BoardCalibration CalibrateFromBoard(const std::vector<std::filesystem::path>& images,
                                    const BoardSpec& board);

// Metres per unit of a reconstruction, from cameras a and b: their baseline in the board frame
// over their baseline `units` in the reconstruction; 0 when no image name shows the board in both.
double MetresPerUnit(const BoardCalibration& a, const BoardCalibration& b, double units);

}  // namespace hdr4d
