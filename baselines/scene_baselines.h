// The scene-level methods of the paper's Tables 1-2 as presets of the trainer's switches
// (method/train/hdr_training_options.h), selected with `hdr4d train --method`:
//   hdr4dgs   the paper's method: log-HDR 4D Gaussians, the Dynamic Tone Mapper, both branches
//   4dgs      plain 4DGS on the LDR images (no HDR, no tone mapping)
//   4dgs-hdr  4DGS with log-HDR colours trained on the HDR ground truth only
//   hdr-gs    HDR-GS on a dynamic scene: the time axis off, the static per-Gaussian MLP tone
//             mapper, the 3D branch only (HDR-GS has no pixel branch), LDR + HDR supervision
#pragma once

#include <string>
#include <vector>

#include "method/train/hdr_training_options.h"

namespace hdr4d::baselines {

// The method names, in the order above.
const std::vector<std::string>& MethodNames();

// The preset of `method`; throws hdr4d::Error listing the valid names for an unknown one.
method::HdrTrainingOptions MethodPreset(const std::string& method);

}  // namespace hdr4d::baselines
