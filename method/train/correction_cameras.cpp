#include "method/train/correction_cameras.h"

#include <algorithm>
#include <utility>

namespace hdr4d::method {

namespace {

// (0, id) for a frame with a camera_id, else (1, index of the first training frame with its
// pose), or (2, 0) when no training frame has it: ordered ids first, then poses.
std::pair<int, int> CorrectionCameraKey(const Frame& f, const std::vector<Frame>& train) {
  if (f.camera_id >= 0) return {0, f.camera_id};
  for (std::size_t i = 0; i < train.size(); ++i) {
    if (train[i].camera_id < 0 &&
        train[i].camera.world_from_cam_gl == f.camera.world_from_cam_gl)
      return {1, static_cast<int>(i)};
  }
  return {2, 0};
}

}  // namespace

const std::vector<int>& CorrectionCameras::Of(Split split) const {
  return split == Split::kTrain ? train : split == Split::kTest ? test : val;
}

CorrectionCameras FindCorrectionCameras(const Dataset& dataset) {
  std::vector<std::pair<int, int>> keys;
  for (const Frame& f : dataset.train) keys.push_back(CorrectionCameraKey(f, dataset.train));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  CorrectionCameras out;
  out.count = static_cast<int>(keys.size());
  for (Split split : {Split::kTrain, Split::kTest, Split::kVal}) {
    std::vector<int>& rows =
        split == Split::kTrain ? out.train : split == Split::kTest ? out.test : out.val;
    for (const Frame& f : dataset.FramesOf(split)) {
      const auto it = std::lower_bound(keys.begin(), keys.end(),
                                       CorrectionCameraKey(f, dataset.train));
      const bool found = it != keys.end() && *it == CorrectionCameraKey(f, dataset.train) &&
                         it->first != 2;
      rows.push_back(found ? static_cast<int>(it - keys.begin()) : -1);
    }
  }
  return out;
}

}  // namespace hdr4d::method
