// The SIMD products of the appearance (dense_simd.h) against plain double sums, and the float
// MLP on them against the Eigen reference (app_mlp.h), on every SIMD target this CPU has.
#include "baselines/hexplane/dense_simd.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "baselines/hexplane/app_mlp.h"
#include "method/raster/simd_targets_for_test.h"

namespace hdr4d::baselines::hexplane {
namespace {

std::vector<float> RandomValues(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// One product in every layout the appearance uses: A plain or transposed, C replaced or added
// to, C wider than n (its row stride), shapes with tails of every vector width.
void CheckProduct(int m, int n, int k, bool transposed, bool accumulate) {
  SCOPED_TRACE(::testing::Message() << m << "x" << n << "x" << k << (transposed ? " A^T" : "")
                                    << (accumulate ? " +=" : ""));
  const std::ptrdiff_t ldc = n + 3;
  const std::vector<float> a = RandomValues(std::size_t(m) * k + 1, 1);
  const std::vector<float> b = RandomValues(std::size_t(k) * n + 1, 2);
  const std::vector<float> c0 = RandomValues(std::size_t(m) * ldc + 1, 3);
  const std::ptrdiff_t a_row = transposed ? 1 : k, a_col = transposed ? m : 1;
  std::vector<float> c = c0;
  DenseProduct(m, n, k, a.data(), a_row, a_col, b.data(), n, c.data(), ldc, accumulate);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < ldc; ++j) {
      const float got = c[std::size_t(i) * ldc + j];
      if (j >= n) {  // past n: untouched
        ASSERT_EQ(got, c0[std::size_t(i) * ldc + j]) << i << "," << j;
        continue;
      }
      double sum = accumulate ? c0[std::size_t(i) * ldc + j] : 0.0, size = std::abs(sum);
      for (int kk = 0; kk < k; ++kk) {
        const double p = double(a[i * a_row + kk * a_col]) * b[std::size_t(kk) * n + j];
        sum += p;
        size += std::abs(p);
      }
      ASSERT_NEAR(got, sum, 1e-6 * (size + 1)) << i << "," << j;
    }
}

TEST(HexPlaneDense, ProductMatchesDoubleSumsOnEveryTarget) {
  const int ran = method::ForEachCompiledTarget([] {
    for (bool transposed : {false, true})
      for (bool accumulate : {false, true})
        for (const auto& [m, n, k] : std::vector<std::array<int, 3>>{
                 {1, 1, 1}, {3, 27, 144}, {7, 3, 128}, {5, 150, 128}, {9, 128, 150},
                 {4, 33, 600}, {2, 17, 0}, {0, 5, 5}, {6, 64, 1}})
          CheckProduct(m, n, k, transposed, accumulate);
  });
  EXPECT_GE(ran, method::MinimumTargetRuns());
}

// The reference's MLP (150-128-128-3) on 37 samples: forward outputs and every gradient agree
// with Eigen's (BatchMlpForward/Backward in float) to float rounding.
void CheckMlp(bool sigmoid) {
  AppMlpShape s;
  s.sigmoid_output = sigmoid;
  const method::MlpShape layers = s.Layers();
  constexpr int kRows = 37;
  const std::vector<float> params = InitAppMlp(s, 5);
  const std::vector<float> xv = RandomValues(std::size_t(kRows) * s.Inputs(), 6);
  const std::vector<float> uv = RandomValues(std::size_t(kRows) * 3, 7);
  const RowMatrix<float> x = Eigen::Map<const RowMatrix<float>>(xv.data(), kRows, s.Inputs());
  const RowMatrix<float> up = Eigen::Map<const RowMatrix<float>>(uv.data(), kRows, 3);
  std::vector<RowMatrix<float>> ref_acts, acts;
  BatchMlpForward(layers, params.data(), x, &ref_acts);
  std::vector<float> ref_grad(params.size(), 0.5f), grad(params.size(), 0.5f);
  RowMatrix<float> ref_dx, dx;
  BatchMlpBackward(layers, params.data(), x, ref_acts, up, ref_grad.data(), &ref_dx);
  method::ForEachCompiledTarget([&] {
    AppMlpForward(layers, params.data(), x, &acts);
    for (int l = 0; l < layers.layers(); ++l)
      ASSERT_LT((acts[l] - ref_acts[l]).cwiseAbs().maxCoeff(), 1e-5f) << "layer " << l;
    std::fill(grad.begin(), grad.end(), 0.5f);  // added to, as the reference
    AppMlpBackward(layers, params.data(), x, acts, up, grad.data(), &dx);
    for (std::size_t i = 0; i < grad.size(); ++i)
      ASSERT_NEAR(grad[i], ref_grad[i], 1e-4f * (1 + std::abs(ref_grad[i]))) << "parameter " << i;
    ASSERT_LT((dx - ref_dx).cwiseAbs().maxCoeff(), 1e-5f);
  });
}

TEST(HexPlaneDense, MlpWithSigmoidOutputMatchesEigenReferenceOnEveryTarget) { CheckMlp(true); }
TEST(HexPlaneDense, MlpWithLinearOutputMatchesEigenReferenceOnEveryTarget) { CheckMlp(false); }

}  // namespace
}  // namespace hdr4d::baselines::hexplane
