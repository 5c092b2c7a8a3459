// The optimiser step fused into the backward: RenderBackward hands over each block of Gaussians
// as soon as its gradient rows are final, and the block's rows of every model group are stepped
// there, while the gradients are still in cache (AdamRowStep, adam.h). The Adam update is
// memory-bound at ~160 floats per Gaussian; this saves reading the gradients back from memory,
// writing the colour rows there at all, and the separate finite check.
#pragma once

#include <string>
#include <vector>

#include "method/gaussian/gradient_rows.h"
#include "method/optim/adam.h"

namespace hdr4d::method {

// The rows_done callback that steps `step`, begun for the model groups `groups` (names from
// kModelGroups, any subset, in BeginRowStep's order): colour rows from the callback, the others
// from their bound buffers. `step` must outlive the backward. Empty when `groups` is empty.
GradientRowsDone StepModelRows(const std::vector<std::string>& groups, AdamRowStep* step);

}  // namespace hdr4d::method
