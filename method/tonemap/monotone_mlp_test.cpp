#include "method/tonemap/monotone_mlp.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::ExpectGradientsMatch;
using testing::FdVector;
using testing::NumericGradient;

// The Dynamic Tone Mapper's curve shape (x and a 2-vector context) and the static MLP's.
const MlpShape kCurve{{3, 16, 16, 1}, MlpOutput::kSigmoid};
const MlpShape kStatic{{1, 32, 1}, MlpOutput::kSigmoid};

std::vector<double> RandomParams(const MlpShape& shape, unsigned seed) {
  std::vector<double> p(shape.NumParams());
  MlpInit(shape, seed, p.data());
  for (double& v : p) v *= 3.0;  // steeper than PyTorch's start: kinks inside the test range
  return p;
}

double Eval(const MlpShape& shape, const std::vector<double>& stored, double x, double f0) {
  std::vector<double> eff(stored.size()), in = {x, f0, -0.3}, cache(shape.CacheSize());
  MonotoneEffective(shape, stored.data(), eff.data());
  double y;
  MlpForward(shape, eff.data(), in.data(), &y, cache.data());
  return y;
}

TEST(MonotoneMlp, ConstrainedWeightsAreThePathsFromInputZero) {
  // {3, 16, 16, 1}: W1 16x3 (column 0 constrained), b1, W2 16x16, b2, W3 1x16, b3.
  EXPECT_TRUE(IsMonotoneWeight(kCurve, 0));
  EXPECT_FALSE(IsMonotoneWeight(kCurve, 1));
  EXPECT_FALSE(IsMonotoneWeight(kCurve, 2));
  EXPECT_TRUE(IsMonotoneWeight(kCurve, 3));
  EXPECT_FALSE(IsMonotoneWeight(kCurve, 48));  // b1
  EXPECT_TRUE(IsMonotoneWeight(kCurve, 64));   // W2
  EXPECT_FALSE(IsMonotoneWeight(kCurve, 64 + 256));  // b2
  EXPECT_TRUE(IsMonotoneWeight(kCurve, 64 + 256 + 16));  // W3
  EXPECT_FALSE(IsMonotoneWeight(kCurve, kCurve.NumParams() - 1));  // b3
  const std::vector<double> p = RandomParams(kCurve, 1);
  std::vector<double> eff(p.size());
  MonotoneEffective(kCurve, p.data(), eff.data());
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(std::abs(eff[i]), std::abs(p[i])) << i;
    if (!IsMonotoneWeight(kCurve, i)) {
      EXPECT_EQ(eff[i], p[i]) << i;
    }
  }
  // Signs: W1[1][0] is an odd (falling) unit's; W2[0][1] joins a rising unit to a falling one;
  // W2[1][1] two falling ones; W3[0][1] a falling unit's output weight.
  EXPECT_LE(eff[3], 0.0);
  EXPECT_LE(eff[64 + 1], 0.0);
  EXPECT_GE(eff[64 + 16 + 1], 0.0);
  EXPECT_LE(eff[64 + 256 + 16 + 1], 0.0);
}

// Rising and falling units together leave no floor or ceiling: the curve runs from 0 to 1.
TEST(MonotoneMlp, CurvesReachZeroAndOne) {
  for (unsigned seed = 0; seed < 20; ++seed) {
    const std::vector<double> p = RandomParams(kCurve, seed);
    EXPECT_LT(Eval(kCurve, p, -1e4, 0.5), 1e-3) << seed;
    EXPECT_GT(Eval(kCurve, p, 1e4, 0.5), 1 - 1e-3) << seed;
  }
}

// Whatever the stored weights and the context, the curve never decreases in x.
TEST(MonotoneMlp, CurvesAreNonDecreasingForAnyWeightsAndContext) {
  for (unsigned seed = 0; seed < 20; ++seed) {
    const std::vector<double> p = RandomParams(kCurve, seed);
    for (double f0 : {-2.0, 0.0, 1.5}) {
      double previous = -1;
      for (double x = -30; x <= 30; x += 0.01) {
        const double y = Eval(kCurve, p, x, f0);
        ASSERT_GE(y, previous - 1e-15) << "seed " << seed << " x " << x;
        previous = y;
      }
    }
  }
}

// d/dstored of the network on the effective weights, in double: the chain through |p|.
TEST(MonotoneMlp, GradientThroughTheAbsoluteValueMatchesFiniteDifferences) {
  for (const MlpShape* shape : {&kCurve, &kStatic}) {
    const std::vector<double> p = RandomParams(*shape, 7);
    const std::vector<double> xs = {-2.3, -0.7, 0.4, 1.9, 3.3};
    std::vector<double> in(shape->inputs(), 0.25), cache(shape->CacheSize());
    std::vector<double> eff(p.size()), d_eff(p.size()), d_in(shape->inputs()),
        back(2 * shape->MaxWidth()), d_stored(p.size(), 0.0);
    MonotoneEffective(*shape, p.data(), eff.data());
    for (double x : xs) {
      in[0] = x;
      double y;
      MlpForward(*shape, eff.data(), in.data(), &y, cache.data());
      const double one = 1.0;
      std::fill(d_eff.begin(), d_eff.end(), 0.0);
      MlpBackward(*shape, eff.data(), in.data(), cache.data(), &one, d_in.data(), d_eff.data(),
                  back.data());
      MonotoneGradientAdd(*shape, p.data(), d_eff.data(), d_stored.data());
    }
    const FdVector numeric = NumericGradient(
        [&](const FdVector& v) {
          std::vector<double> q(v.data(), v.data() + v.size()), e(q.size()), c(shape->CacheSize());
          MonotoneEffective(*shape, q.data(), e.data());
          std::vector<double> i2 = in;
          double sum = 0;
          for (double x : xs) {
            i2[0] = x;
            double y;
            MlpForward(*shape, e.data(), i2.data(), &y, c.data());
            sum += y;
          }
          return sum;
        },
        Eigen::Map<const FdVector>(p.data(), p.size()), 1e-6);
    ExpectGradientsMatch(Eigen::Map<const FdVector>(d_stored.data(), d_stored.size()), numeric,
                         1e-6);
  }
}

}  // namespace
}  // namespace hdr4d::method
