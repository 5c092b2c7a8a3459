// The HDR-4DGS switches of a run resolved against its scene and tone mapper (ResolveHdrTraining,
// method/train/hdr_training_options.h): what one training view computes, and so which outputs a
// finished run renders (view_renderer.h) and how. Saved in a run's config.json as "resolved".
#pragma once

#include <nlohmann/json.hpp>

#include "method/render/pixel_log.h"

namespace hdr4d::method {

struct ResolvedHdrTraining {
  bool hdr_colors = true;              // log-HDR colours and an HDR raster (false: plain LDR 4DGS)
  bool ldr_gaussian = false;           // 3D branch LDR term (6-channel raster)
  bool ldr_pixel = false;              // 2D branch LDR term
  bool hdr = false;                    // HDR term (views with HDR ground truth)
  bool hdr_head = false;               // an HDR head fitted after the last iteration
  bool final_ldr_from_pixels = false;  // the LDR output is the 2D branch (whole-image mappers)
  float pixel_log_epsilon = kReferencePixelLogEpsilon;  // the 2D branch's log(HDR + eps)
  nlohmann::json ToJson() const;
};

}  // namespace hdr4d::method
