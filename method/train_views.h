// Training and test views held in memory: the camera, the normalised time and the LDR image in
// 8 bits per channel (a paper-size scene, 280 frames at 800x800, is then 0.5 GB, not 2 GB),
// converted to float one view at a time when it is used.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/dataset.h"

namespace hdr4d::method {

struct TrainView {
  Camera camera;
  float time = 0;
  double exposure = 1;
  std::string name;               // the image's file name (renders are written under it)
  std::vector<std::uint8_t> rgb;  // H x W x 3, display-encoded as stored
  int width() const { return camera.intrinsics.width; }
  int height() const { return camera.intrinsics.height; }
  // The image as floats in [0,1] (H x W x 3) into `out` (resized).
  void ToFloat(std::vector<float>* out) const;
};

// Reads the frames of `split`: RGB, or RGBA composited over `background` (the reference
// composites D-NeRF's RGBA onto black). Integer images are required (the LDR targets).
std::vector<TrainView> LoadViews(const Dataset& dataset, Split split, const float background[3]);

}  // namespace hdr4d::method
