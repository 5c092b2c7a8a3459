#include "method/tonemap/mlp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::ExpectGradientsMatch;
using testing::FdVector;
using testing::NumericGradient;

// L = sum_o weight_o * out_o, and its gradients from MlpBackward.
struct MlpCase {
  MlpShape shape;
  std::vector<double> params, x, weights;

  double Loss(const std::vector<double>& p, const std::vector<double>& in) const {
    std::vector<double> out(shape.outputs()), cache(shape.CacheSize());
    MlpForward(shape, p.data(), in.data(), out.data(), cache.data());
    double l = 0;
    for (int o = 0; o < shape.outputs(); ++o) l += weights[o] * out[o];
    return l;
  }
};

MlpCase MakeCase(std::vector<int> widths, MlpOutput output, unsigned seed) {
  MlpCase c;
  c.shape = {std::move(widths), output};
  c.params.resize(c.shape.NumParams());
  MlpInit(c.shape, seed, c.params.data());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int i = 0; i < c.shape.inputs(); ++i) c.x.push_back(u(rng));
  for (int o = 0; o < c.shape.outputs(); ++o) c.weights.push_back(u(rng));
  return c;
}

void CheckGradients(const MlpCase& c) {
  std::vector<double> out(c.shape.outputs()), cache(c.shape.CacheSize());
  MlpForward(c.shape, c.params.data(), c.x.data(), out.data(), cache.data());
  std::vector<double> dx(c.shape.inputs()), dp(c.params.size(), 0.0),
      scratch(2 * c.shape.MaxWidth());
  MlpBackward(c.shape, c.params.data(), c.x.data(), cache.data(), c.weights.data(), dx.data(),
              dp.data(), scratch.data());

  const FdVector x0 = Eigen::Map<const FdVector>(c.x.data(), c.x.size());
  const FdVector num_x = NumericGradient(
      [&](const FdVector& v) {
        return c.Loss(c.params, {v.data(), v.data() + v.size()});
      },
      x0, 1e-6);
  ExpectGradientsMatch(Eigen::Map<const FdVector>(dx.data(), dx.size()), num_x, 1e-6);

  const FdVector p0 = Eigen::Map<const FdVector>(c.params.data(), c.params.size());
  const FdVector num_p = NumericGradient(
      [&](const FdVector& v) {
        return c.Loss({v.data(), v.data() + v.size()}, c.x);
      },
      p0, 1e-6);
  ExpectGradientsMatch(Eigen::Map<const FdVector>(dp.data(), dp.size()), num_p, 1e-6);
}

TEST(Mlp, GradientsMatchFiniteDifferences) {
  CheckGradients(MakeCase({3, 64, 64, 1}, MlpOutput::kSigmoid, 1));  // a DTM tone curve
  CheckGradients(MakeCase({1, 128, 1}, MlpOutput::kSigmoid, 2));     // the HDR-GS curve
  CheckGradients(MakeCase({1, 128, 1}, MlpOutput::kLinear, 3));
  CheckGradients(MakeCase({4, 8, 5, 3}, MlpOutput::kLinear, 4));
  CheckGradients(MakeCase({2, 7, 3}, MlpOutput::kSigmoid, 5));
  CheckGradients(MakeCase({5, 2}, MlpOutput::kSigmoid, 6));  // no hidden layer
}

TEST(Mlp, BackwardAddsToParameterGradientsAndAcceptsNullInputGradient) {
  const MlpCase c = MakeCase({3, 16, 16, 1}, MlpOutput::kSigmoid, 7);
  std::vector<double> out(1), cache(c.shape.CacheSize()), scratch(2 * c.shape.MaxWidth());
  MlpForward(c.shape, c.params.data(), c.x.data(), out.data(), cache.data());
  std::vector<double> once(c.params.size(), 0.0), twice(c.params.size(), 0.0);
  MlpBackward(c.shape, c.params.data(), c.x.data(), cache.data(), c.weights.data(),
              static_cast<double*>(nullptr), once.data(), scratch.data());
  for (int k = 0; k < 2; ++k) {
    MlpBackward(c.shape, c.params.data(), c.x.data(), cache.data(), c.weights.data(),
                static_cast<double*>(nullptr), twice.data(), scratch.data());
  }
  double largest = 0;
  for (std::size_t i = 0; i < once.size(); ++i) {
    EXPECT_NEAR(twice[i], 2 * once[i], 1e-12);
    largest = std::max(largest, std::abs(once[i]));
  }
  EXPECT_GT(largest, 1e-3);
}

TEST(Mlp, InitFollowsTorchBoundsAndSeed) {
  const MlpShape shape{{3, 64, 64, 1}, MlpOutput::kSigmoid};
  std::vector<float> a(shape.NumParams()), b(a.size()), c(a.size());
  MlpInit(shape, 11, a.data());
  MlpInit(shape, 11, b.data());
  MlpInit(shape, 12, c.data());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Layer 1 (fan-in 3) within 1/sqrt(3); layer 2 (fan-in 64) within 1/8, and it uses that range.
  float max1 = 0, max2 = 0;
  for (std::size_t i = 0; i < 64 * 4; ++i) max1 = std::max(max1, std::abs(a[i]));
  for (std::size_t i = 64 * 4; i < 64 * 4 + 64 * 65; ++i) max2 = std::max(max2, std::abs(a[i]));
  EXPECT_LE(max1, 1 / std::sqrt(3.0f));
  EXPECT_GT(max1, 0.5f);
  EXPECT_LE(max2, 0.125f);
  EXPECT_GT(max2, 0.12f);
}

TEST(Mlp, StableSigmoidAtExtremes) {
  for (double z : {1e4, -1e4, 1e300, -1e300, 710.0, -710.0, 800.0, -800.0}) {
    const double y = StableSigmoid(z);
    EXPECT_TRUE(std::isfinite(y)) << z;
    EXPECT_GE(y, 0.0);
    EXPECT_LE(y, 1.0);
    EXPECT_NEAR(y, z > 0 ? 1.0 : 0.0, 1e-300) << z;
  }
  for (float z : {1e4f, -1e4f, 3e38f, -3e38f, 89.0f, -89.0f, 100.0f, -100.0f}) {
    const float y = StableSigmoid(z);
    EXPECT_TRUE(std::isfinite(y)) << z;
    EXPECT_GE(y, 0.0f);
    EXPECT_LE(y, 1.0f);
  }
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(StableSigmoid(inf), 1.0);
  EXPECT_EQ(StableSigmoid(-inf), 0.0);
  // Matches the plain formula where that is safe, and is symmetric.
  for (double z : {-30.0, -3.0, -0.1, 0.0, 0.1, 3.0, 30.0}) {
    EXPECT_NEAR(StableSigmoid(z), 1.0 / (1.0 + std::exp(-z)), 1e-15) << z;
    EXPECT_NEAR(StableSigmoid(-z), 1.0 - StableSigmoid(z), 1e-15) << z;
  }
  // A saturated sigmoid output gives a zero (not NaN) gradient through MlpBackward.
  const MlpShape shape{{1, 1}, MlpOutput::kSigmoid};
  const double params[2] = {1.0, 0.0}, x = 1e4, dy = 1.0;
  double out, cache[1], dx, dp[2] = {0, 0}, scratch[2];
  MlpForward(shape, params, &x, &out, cache);
  MlpBackward(shape, params, &x, cache, &dy, &dx, dp, scratch);
  EXPECT_EQ(out, 1.0);
  EXPECT_EQ(dx, 0.0);
  EXPECT_EQ(dp[0], 0.0);
}

}  // namespace
}  // namespace hdr4d::method
