// calibrate's radiometry stage: the camera response (one for the rig, or one per camera when
// their curves differ or --per-camera-response asks), HDR fusion of every frame, the cameras'
// gains, and the images/ and hdr/ folders of the dataset.
#pragma once

#include <filesystem>
#include <optional>
#include <vector>

#include "calibration/calibrate.h"
#include "calibration/calibration_report.h"
#include "calibration/capture.h"
#include "core/dataset/dataset.h"

namespace hdr4d {

// Writes images/, hdr/, response.* into `staging` and returns the dataset frames (one per
// bracket) when the rig is known.
std::vector<Frame> RunRadiometry(const Capture& capture, const CalibrateOptions& options,
                                 const std::optional<Rig>& rig, const std::filesystem::path& staging,
                                 CalibrationRecord* record, int* images_written);

// How far the cameras' response shapes differ: the RMS over channels and mid codes (32..223)
// of the log difference between each camera's curve and the first's (each normalised at code
// 128, so a plain gain difference is no difference).
double ResponseSpread(const std::vector<CameraResponse>& responses);

}  // namespace hdr4d
