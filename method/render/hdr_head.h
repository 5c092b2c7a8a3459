// The HDR head of a run as the renderers apply it (`hdr4d train --hdr-head`; method/train/
// hdr_head_fit.h fits it and reads it from a checkpoint): a log-radiance offset d per Gaussian
// and channel that only the HDR channels add (exp(c + d), hdr_color_stage.h; the tone-mapped
// channels stay TM(c + log e)), with a learned background one offset per channel for the
// backdrop's HDR (learned_background.h), and one factor exp(log_scale) on the whole HDR output,
// background included.
#pragma once

#include <vector>

namespace hdr4d::method {

struct HdrHead {
  std::vector<float> offset;      // N x 3, the model's order; empty: no head
  std::vector<float> background;  // 3: the learned background's HDR offset; empty: none
  float log_scale = 0.0f;         // the whole HDR output is multiplied by exp(log_scale)
  bool empty() const { return offset.empty(); }
};

}  // namespace hdr4d::method
