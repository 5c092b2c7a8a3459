// --batch-size B (the reference's batch_size): the loss of a step is the mean of B views'
// losses, so its gradient is the mean of their gradients; the trainer sums each view's
// gradient into one buffer and scales it by 1 / B before the one optimiser step of the batch.
#pragma once

#include <vector>

#include "core/util/error.h"
#include "method/gaussian/gaussian_model.h"

namespace hdr4d::method {

template <typename T>
std::vector<std::vector<T>*> GradientFields(GaussianGradientsT<T>* g) {
  return {&g->xyz,           &g->t,        &g->log_scales, &g->rot_left, &g->rot_right,
          &g->opacity_logit, &g->color_dc, &g->color_rest};
}

// sum += view, field by field (same shape, checked).
template <typename T>
void AddGradients(const GaussianGradientsT<T>& view, GaussianGradientsT<T>* sum) {
  auto from = GradientFields(const_cast<GaussianGradientsT<T>*>(&view));
  auto to = GradientFields(sum);
  for (std::size_t f = 0; f < to.size(); ++f) {
    HDR4D_CHECK(from[f]->size() == to[f]->size());
    for (std::size_t i = 0; i < to[f]->size(); ++i) (*to[f])[i] += (*from[f])[i];
  }
}

// g *= scale.
template <typename T>
void ScaleGradients(T scale, GaussianGradientsT<T>* g) {
  for (std::vector<T>* field : GradientFields(g))
    for (T& v : *field) v *= scale;
}

}  // namespace hdr4d::method
