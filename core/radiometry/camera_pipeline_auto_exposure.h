// Auto-exposure as a phone does it: the camera meters each frame's log mean luminance L and
// follows it with a lag, an exponential moving average over time,
//   S_0 = L_0,   S_k = S_{k-1} + (1 - exp(-(t_k - t_{k-1}) / lag)) (L_k - S_{k-1}),
// (lag = 0: S = L) and sets the gain  g_k = exp(strength (L_ref - S_k)),  where L_ref is the
// mean of L over every view of the sequence (so gains stay near 1 and the nominal exposures
// keep their meaning). A scene that doubles in brightness gets, once the lag has passed, a gain
// that halves (strength 1).
//   rig scope:    one meter for the rig: L_k is the mean of the views' L at timestamp t_k, and
//                 every camera at t_k gets the same gain.
//   camera scope: each camera meters its own view over its own timestamps.
#pragma once

#include <string>
#include <vector>

#include "core/radiometry/camera_pipeline.h"

namespace hdr4d {

// One gain per view, in the order of `views` (views[i].stats.log_mean is L). scope: "rig" or
// "camera"; lag >= 0; strength in [0, 1].
std::vector<double> AutoExposureGains(const std::vector<PipelineView>& views,
                                      const std::string& scope, double lag, double strength);

}  // namespace hdr4d
