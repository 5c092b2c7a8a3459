#include "baselines/hexplane/feature_plane.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/finite_difference.h"

namespace hdr4d::baselines::hexplane {
namespace {

using hdr4d::testing::FdCheck;
using hdr4d::testing::FdVector;
// Bilinear lookups, TV and L1 are polynomial (or piecewise linear) in the plane values: central
// differences are exact up to rounding at this step.
constexpr FdCheck kFd{1e-6, 1e-6};

Plane<double> RandomPlane(int c, int h, int w, unsigned seed) {
  Plane<double> p(c, h, w);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n;
  for (double& v : p.data) v = n(rng);
  return p;
}

FdVector AsVector(const Plane<double>& p) {
  return Eigen::Map<const FdVector>(p.data.data(), p.data.size());
}

TEST(FeaturePlane, CornersReadTheGridAndTheCentreAveragesFour) {
  const Plane<double> p = RandomPlane(2, 3, 4, 1);
  double out[2];
  Gather(p, MakeTap(p, -1.0, -1.0), out);
  EXPECT_DOUBLE_EQ(out[1], p.data[1]);
  Gather(p, MakeTap(p, 1.0, 1.0), out);
  EXPECT_DOUBLE_EQ(out[0], p.data[(2 * 4 + 3) * 2]);
  // u = -1/3 is between columns 1 and 2 (of 0..3) at their middle; v = 0 is row 1.
  Gather(p, MakeTap(p, 0.0, 0.0), out);
  EXPECT_NEAR(out[0], 0.5 * (p.data[(1 * 4 + 1) * 2] + p.data[(1 * 4 + 2) * 2]), 1e-12);
}

TEST(FeaturePlane, ScatterIsTheGradientOfGather) {
  Plane<double> p = RandomPlane(3, 4, 5, 2);
  const double u = 0.37, v = -0.61, up[3] = {0.3, -1.2, 0.8};
  auto loss = [&](const FdVector& x) {
    Plane<double> q = p;
    for (int i = 0; i < x.size(); ++i) q.data[i] = x(i);
    double out[3];
    Gather(q, MakeTap(q, u, v), out);
    return out[0] * up[0] + out[1] * up[1] + out[2] * up[2];
  };
  Plane<double> grad(3, 4, 5);
  Scatter(MakeTap(p, u, v), up, &grad);
  kFd.ExpectMatch(AsVector(grad), kFd.Gradient(loss, AsVector(p)));
}

TEST(FeaturePlane, TotalVariationAndL1Gradients) {
  const Plane<double> p = RandomPlane(2, 3, 4, 3);
  auto tv = [&](const FdVector& x) {
    Plane<double> q = p;
    for (int i = 0; i < x.size(); ++i) q.data[i] = x(i);
    return TotalVariation<double>(q, 1.0, 2.0, 1.0, nullptr) + 0.3 * MeanAbs<double>(q, 1, nullptr);
  };
  Plane<double> grad(2, 3, 4);
  TotalVariation<double>(p, 1.0, 2.0, 1.0, &grad);
  MeanAbs<double>(p, 0.3, &grad);
  kFd.ExpectMatch(AsVector(grad), kFd.Gradient(tv, AsVector(p)));
}

TEST(FeaturePlane, TotalVariationOfAConstantPlaneIsZero) {
  Plane<double> p(2, 3, 3);
  std::fill(p.data.begin(), p.data.end(), 0.7);
  EXPECT_EQ(TotalVariation<double>(p, 1.0, 2.0, 1.0, nullptr), 0.0);
}

TEST(FeaturePlane, ResizeKeepsALinearRampAndTheCorners) {
  Plane<double> p(1, 2, 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) p.data[y * 3 + x] = 2.0 * x + 5.0 * y;
  const Plane<double> r = Resized(p, 5, 7);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x)
      EXPECT_NEAR(r.data[y * 7 + x], 2.0 * (x * 2.0 / 6) + 5.0 * (y / 4.0), 1e-12);
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
