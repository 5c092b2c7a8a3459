// What a scene needs: the facts about a dataset that let later stages skip work (ARCHITECTURE §1: a
// static scene trains no time axis, a scene without HDR ground truth computes no HDR loss, ...).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/dataset/dataset.h"

namespace hdr4d {

struct SceneProfile {
  bool dynamic = false;          // more than one distinct (normalised) time
  bool multi_exposure = false;   // more than one distinct exposure value
  bool has_hdr_gt = false;       // every test frame has an HDR ground truth (and there are some)
  bool partial_hdr_gt = false;   // some frames have HDR ground truth, but not every test frame
  bool hdr_gt_in_train = false;  // some training frame has HDR ground truth (an HDR loss can run)
  bool multi_view = false;       // several distinct cameras see the same instant (or camera_id's)
  int num_cameras = 0;  // distinct camera_id when given, else distinct poses (monocular: ~frames)
  int num_timestamps = 0;  // distinct normalised times
  int num_frames = 0;
  int num_hdr_frames = 0;             // frames with an exr_file_path
  std::vector<double> exposures;      // distinct, sorted ascending (seconds)
  // The exposures were not read: written as seconds they look like log2 stops
  // (Dataset::exposures_look_like_stops); `exposures` is then empty.
  bool exposures_unread = false;
  double time_min = 0, time_max = 0;  // normalised
  int width = 0, height = 0;          // of the first frame (every frame shares it in a valid scene)

  // One line per fact, each saying what later stages do or skip because of it.
  std::string Describe() const;
  nlohmann::json ToJson() const;
};

// Values closer than these count as the same time / exposure / pose.
inline constexpr double kSameTimeTolerance = 1e-9;
inline constexpr double kSameExposureRelTolerance = 1e-9;
inline constexpr double kSamePoseTolerance = 1e-6;

SceneProfile ProfileScene(const Dataset& dataset);

}  // namespace hdr4d
