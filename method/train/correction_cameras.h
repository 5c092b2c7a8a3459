// Which training camera took each frame, for the per-camera correction
// (method/tonemap/camera_correction.h): the row of ToneFrame::camera_index.
//
// A camera is the frame's camera_id where the JSON gives one (datagen and calibrate write it),
// else its pose: frames with exactly the same world_from_cam matrix are one camera (a fixed rig
// without ids). The training split's cameras, in the order of their ids (id-less poses after,
// in order of first appearance), are rows 0 .. K-1; a frame of any split from one of them gets
// its row, any other frame -1 (a held-out camera: the identity). A monocular scene, whose
// camera moves, has a camera per pose: its held-out frames all get -1.
#pragma once

#include <vector>

#include "core/dataset/dataset.h"

namespace hdr4d::method {

struct CorrectionCameras {
  int count = 0;                          // K, the training cameras
  std::vector<int> train, test, val;      // per frame of each split: its row, or -1
  const std::vector<int>& Of(Split split) const;
};

CorrectionCameras FindCorrectionCameras(const Dataset& dataset);

}  // namespace hdr4d::method
