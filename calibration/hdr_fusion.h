// Fusing one view's brackets into linear HDR with a recovered response: an inverse-variance
// weighted average of each bracket's radiance estimate (calibration/bracket_noise.h: weights
// that know the exposure time, the black level and saturation), except where the brackets disagree because something
// moved between them; there the best-exposed bracket alone is used (no ghosts).
#pragma once

#include <vector>

#include "calibration/bracket_noise.h"
#include "calibration/response_recovery.h"
#include "core/image/image.h"

namespace hdr4d {

struct FusionOptions {
  // Brackets whose log radiance differs from the reference bracket's by more than this, where
  // both are well exposed, mark the pixel as moving (ln 1.5: far above 8-bit quantisation
  // noise in mid-tones).
  double motion_log_threshold = 0.405;
  int motion_dilation = 2;  // pixels: moving edges blur over a few pixels
  bool detect_motion = true;
};

struct FusionResult {
  Image hdr;               // linear, radiance per second (x / exposure)
  double motion_fraction = 0;  // pixels that fell back to one bracket
  int reference_bracket = 0;   // the best-exposed bracket overall
  double dynamic_range_stops = 0;  // log2 of the 99.9th / 0.1th percentile luminance (> 0)
  std::vector<ChannelNoise> noise;  // black level, read noise and saturation per channel
};

// Brackets must share size and channel count with the response's channels; checked.
FusionResult FuseBrackets(const std::vector<Bracket>& brackets,
                          const CameraResponse& response,
                          const FusionOptions& options = {});

}  // namespace hdr4d
