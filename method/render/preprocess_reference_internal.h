// Internal to the reference preprocess (preprocess_reference.cpp) and its tests: the geometry's
// backward of one Gaussian, exposed so that it can be checked alone against finite differences
// of ConditionAt (preprocess_geometry_backward_test.cpp).
#pragma once

#include <cstddef>

#include "method/render/frame_state.h"

namespace hdr4d::method::detail {

// The geometry's backward of visible Gaussian i (conditioned as `c`, ConditionAt's result) from
// the gradients of the conditional mean (dmean3), covariance (dcov3, the full 3x3 matrix) and
// the marginal (dmarginal, 4D only): through the slice, the 4D (or 3D) covariance and the
// rotation to the stored xyz, t, log_scales, rot_left and rot_right, ADDED to `grads`.
template <typename T>
void GeometryBackward(const GaussianModelT<T>& model,
                      std::size_t i,
                      T time,
                      const ConditionalGaussian<T>& c,
                      const Vec3<T>& dmean3,
                      const Mat3<T>& dcov3,
                      T dmarginal,
                      GaussianGradientsT<T>* grads);

}  // namespace hdr4d::method::detail
