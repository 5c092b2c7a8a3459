// GeometryBackward (preprocess_reference_internal.h), the reference preprocess's backward from
// the conditional 3D Gaussian to the stored geometry: driven alone from random gradients of the
// conditional mean, covariance and marginal, against central differences in double of
// ConditionAt (the forward it inverts), in the 4D and the 3D mode.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "method/render/preprocess_common.h"
#include "method/render/preprocess_reference_internal.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::FdCheck;
using testing::FdVector;

// Steps of 1e-6 on smooth double functions of size ~1: truncation and rounding both ~1e-10.
constexpr FdCheck kFd{1e-6, 1e-6};
constexpr double kTime = 0.4;
constexpr int kGaussians = 3;

GaussianModelT<double> RandomModel(bool temporal, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  GaussianModelT<double> m;
  m.temporal = temporal;
  m.Resize(kGaussians);
  for (double& v : m.xyz) v = u(rng);
  for (double& v : m.t) v = kTime + 0.2 * u(rng);  // marginals well above zero
  for (double& v : m.log_scales) v = -1.0 + 0.5 * u(rng);
  // Unnormalised quaternions that mix the axes (and, in 4D, time with space).
  for (double& v : m.rot_left) v = 0.5 + u(rng);
  for (double& v : m.rot_right) v = 0.5 + u(rng);
  return m;
}

// The geometry buffers, flattened: xyz | t | log_scales | rot_left | rot_right.
std::vector<std::vector<double>*> Buffers(GaussianModelT<double>& m) {
  return {&m.xyz, &m.t, &m.log_scales, &m.rot_left, &m.rot_right};
}
FdVector Flatten(GaussianModelT<double> m) {
  std::vector<double> all;
  for (const std::vector<double>* b : Buffers(m)) all.insert(all.end(), b->begin(), b->end());
  return Eigen::Map<const FdVector>(all.data(), all.size());
}
GaussianModelT<double> Unflatten(GaussianModelT<double> m, const FdVector& x) {
  int k = 0;
  for (std::vector<double>* b : Buffers(m))
    for (double& v : *b) v = x(k++);
  return m;
}

TEST(PreprocessGeometry, GeometryBackwardMatchesFiniteDifferencesInDouble) {
  for (bool temporal : {true, false}) {
    SCOPED_TRACE(temporal ? "4D" : "3D");
    const GaussianModelT<double> model = RandomModel(temporal, temporal ? 3 : 4);
    // Upstream gradients per Gaussian; dcov3 is a full (unsymmetric) matrix, as the loss below
    // reads every entry of the covariance.
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Vec3<double>> dmean(kGaussians);
    std::vector<Mat3<double>> dcov(kGaussians);
    std::vector<double> dmarginal(kGaussians);
    for (int i = 0; i < kGaussians; ++i) {
      for (int a = 0; a < 3; ++a) dmean[i][a] = u(rng);
      for (int a = 0; a < 9; ++a) dcov[i](a / 3, a % 3) = u(rng);
      dmarginal[i] = temporal ? u(rng) : 0.0;
    }
    const auto loss = [&](const FdVector& x) {
      const GaussianModelT<double> m = Unflatten(model, x);
      double l = 0;
      for (int i = 0; i < kGaussians; ++i) {
        const ConditionalGaussian<double> c = detail::ConditionAt(m, i, kTime);
        l += dmean[i].dot(c.mean) + (dcov[i].array() * c.cov.array()).sum() +
             dmarginal[i] * c.marginal;
      }
      return l;
    };
    GaussianGradientsT<double> grads;
    grads.ZerosLike(model);
    for (int i = 0; i < kGaussians; ++i) {
      const ConditionalGaussian<double> c = detail::ConditionAt(model, i, kTime);
      if (temporal) ASSERT_GT(c.marginal, 0.05);
      detail::GeometryBackward(model, std::size_t(i), kTime, c, dmean[i], dcov[i], dmarginal[i],
                               &grads);
    }
    // In 3D the numeric gradient of t, the time scale and rot_right is zero, and so must be the
    // analytic one.
    kFd.ExpectMatch(Flatten(grads), kFd.Gradient(loss, Flatten(model)));
  }
}

}  // namespace
}  // namespace hdr4d::method
