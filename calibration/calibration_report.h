// The calibration report: report.md (tables and the response plot, readable on GitHub) and
// calibration.json with the same numbers for scripts.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "calibration/bracket_noise.h"
#include "calibration/camera_gains.h"
#include "calibration/rig_geometry.h"

namespace hdr4d {

struct FrameRecord {
  std::string camera;
  int frame = 0;
  double dynamic_range_stops = 0;
  double motion_fraction = 0;
  int reference_bracket = 0;
  std::vector<ChannelNoise> noise;  // the black level, read noise and saturation fusion used
};

struct CalibrationRecord {
  std::optional<Rig> rig;
  bool geometry_run = false;  // this run computed the rig (else it was read from rig.json)
  std::string response_method;  // empty: radiometry not run
  bool per_camera_response = false;  // each camera fused with its own curve (response_<cam>.csv)
  double response_spread = 0;        // ResponseSpread of the cameras' own curves
  std::vector<FrameRecord> frames;
  std::optional<CameraGains> gains;  // cameras' agreement (radiometry with a rig of 2+ cameras)
  bool gains_applied = false;
  std::vector<std::string> warnings;
  std::string test_camera;
  double seconds_geometry = 0, seconds_radiometry = 0;
};

void WriteCalibrationReport(const std::filesystem::path& folder, const CalibrationRecord& record);

}  // namespace hdr4d
