// The hand-over between the renderer's backward and the optimiser: a callback told which blocks
// of Gaussians have final gradient rows. Here, below both, so that the optimiser (method/optim/)
// need not link the renderer (method/render/) for a type.
#pragma once

#include <cstdint>
#include <functional>

namespace hdr4d::method {

// The colour gradient rows of a block of Gaussians [begin, end): colour_dc and colour_rest of
// Gaussian begin + r at color_dc + r * channels and color_rest + r * rest_stride.
template <typename T>
struct GradientRowsT {
  const T* color_dc;
  const T* color_rest;
};
using GradientRows = GradientRowsT<float>;

// Called with Gaussian ranges [begin, end) whose gradient rows are final, from worker threads,
// each Gaussian exactly once per backward: the trainer's optimiser step runs here, on rows still
// in cache (AdamRowStep, method/optim/adam.h). The colour rows are passed (see
// PreprocessBackward, method/render/preprocess.h); the other rows are in `grads`.
template <typename T>
using GradientRowsDoneT =
    std::function<void(std::int64_t begin, std::int64_t end, const GradientRowsT<T>& colour)>;
using GradientRowsDone = GradientRowsDoneT<float>;

}  // namespace hdr4d::method
