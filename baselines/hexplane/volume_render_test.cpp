#include "baselines/hexplane/volume_render.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::baselines::hexplane {
namespace {

using hdr4d::testing::FdCheck;
using hdr4d::testing::FdVector;
// Smooth in every input; step 1e-6 in double leaves ~1e-10 truncation and rounding.
constexpr FdCheck kFd{1e-6, 1e-6};

constexpr int kN = 5, kK = 6;
const double kShift = -1.0;
const double kDelta[kN] = {0.5, 0.7, 0.2, 0.9, 0.0};  // the last step is 0, as the reference's
const double kBackground[kK] = {0.2, 0.4, 0.1, 0.0, 1.0, 0.5};
const double kUp[kK] = {0.7, -0.3, 1.1, 0.4, -0.9, 0.2};

// x = features (n) then colours (n x K); returns up . pixel.
double Loss(const FdVector& x) {
  double alpha[kN], weight[kN], out[kK];
  const double t = CompositeWeights(x.data(), kDelta, kN, kShift, alpha, weight);
  Composite(weight, x.data() + kN, kN, kK, t, kBackground, out);
  double l = 0;
  for (int k = 0; k < kK; ++k) l += kUp[k] * out[k];
  return l;
}

TEST(VolumeRender, BackwardMatchesFiniteDifferences) {
  FdVector x(kN + kN * kK);
  x << 0.3, 2.0, -1.5, 4.0, 0.5, 0.1, 0.9, 0.4, 2.0, 0.1, 0.3, 0.8, 0.2, 0.6, 1.5, 0.7, 0.2, 0.3,
      0.3, 0.9, 0.4, 0.1, 3.0, 0.5, 0.5, 0.5, 0.2, 0.8, 0.6, 0.1, 0.7, 0.4, 0.6, 0.2, 0.9;
  double alpha[kN], weight[kN];
  CompositeWeights(x.data(), kDelta, kN, kShift, alpha, weight);
  FdVector analytic(x.size());
  CompositeBackward(x.data(), kDelta, alpha, weight, x.data() + kN, kN, kK, kShift, kBackground,
                    kUp, analytic.data() + kN, analytic.data());
  kFd.ExpectMatch(analytic, kFd.Gradient(Loss, x));
}

TEST(VolumeRender, OpaqueSampleHidesWhatIsBehindAndEmptyRayShowsTheBackground) {
  const double f[2] = {60.0, 60.0}, d[2] = {1.0, 1.0}, c[2] = {0.25, 0.75}, b = 0.5;
  double alpha[2], weight[2], out;
  double t = CompositeWeights(f, d, 2, 0.0, alpha, weight);
  Composite(weight, c, 2, 1, t, &b, &out);
  EXPECT_NEAR(out, 0.25, 1e-12);
  const double empty[2] = {-80.0, -80.0};
  t = CompositeWeights(empty, d, 2, 0.0, alpha, weight);
  Composite(weight, c, 2, 1, t, &b, &out);
  EXPECT_NEAR(out, 0.5, 1e-12);
  EXPECT_EQ(Softplus(1000.0), 1000.0);  // no overflow
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
