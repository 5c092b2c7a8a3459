// The learned background (background_env.h): its backward against double-precision finite
// differences for both colour models, and what degree 0 and 2 mean.
#include "baselines/hexplane/background_env.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace hdr4d::baselines::hexplane {
namespace {

constexpr double kMaxLog = 30.0;

// sum_k w_k out_k for coefficients c and offset o.
double Loss(const std::vector<double>& c, int n, const float dir[3], int K, double offset) {
  double pre[3], out[6];
  BackgroundForward(c.data(), n, dir, K, offset, -0.4, kMaxLog, pre, out);
  double l = 0;
  for (int k = 0; k < K; ++k) l += (0.3 + 0.2 * k) * out[k];
  return l;
}

void CheckBackward(int K) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  const int n = 9;
  std::vector<double> c(3 * n);
  for (double& v : c) v = u(rng);
  float dir[3] = {0.3f, -0.5f, 0.7f};
  const float len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  for (float& d : dir) d /= len;
  const double offset = 0.25;
  double pre[3], out[6], w[6];
  BackgroundForward(c.data(), n, dir, K, offset, -0.4, kMaxLog, pre, out);
  for (int k = 0; k < K; ++k) w[k] = 0.3 + 0.2 * k;
  std::vector<double> dc(3 * n, 0.0);
  double doffset = 0;
  BackgroundBackward(n, dir, K, offset, -0.4, kMaxLog, pre, w, dc.data(), &doffset);
  const double h = 1e-6;
  for (int i = 0; i < 3 * n; ++i) {
    std::vector<double> p = c, m = c;
    p[i] += h;
    m[i] -= h;
    const double numeric = (Loss(p, n, dir, K, offset) - Loss(m, n, dir, K, offset)) / (2 * h);
    EXPECT_NEAR(dc[i], numeric, 1e-7 + 1e-6 * std::abs(numeric)) << "coefficient " << i;
  }
  const double numeric =
      (Loss(c, n, dir, K, offset + h) - Loss(c, n, dir, K, offset - h)) / (2 * h);
  if (K == 3) {
    EXPECT_EQ(doffset, 0.0);  // the LDR model has no exposure
  } else {
    EXPECT_NEAR(doffset, numeric, 1e-7 + 1e-6 * std::abs(numeric));
    EXPECT_GT(std::abs(numeric), 1e-3);  // the offset matters: the check can fail
  }
}

TEST(BackgroundEnv, BackwardMatchesFiniteDifferencesLdr) { CheckBackward(3); }
TEST(BackgroundEnv, BackwardMatchesFiniteDifferencesLogHdr) { CheckBackward(6); }

TEST(BackgroundEnv, OneColourIsTheSameEverywhereAndTheEnvironmentIsNot) {
  const float a[3] = {0.0f, 0.0f, 1.0f}, b[3] = {1.0f, 0.0f, 0.0f};
  std::vector<double> c(27, 0.0);
  c[0] = 1.0;   // degree 0, red
  c[2 * 3 + 1] = 1.5;  // y_2 (the z term), green
  double pre_a[3], pre_b[3], out_a[3], out_b[3];
  BackgroundForward(c.data(), 1, a, 3, 0.0, 0.0, kMaxLog, pre_a, out_a);
  BackgroundForward(c.data(), 1, b, 3, 0.0, 0.0, kMaxLog, pre_b, out_b);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(out_a[k], out_b[k]);
  BackgroundForward(c.data(), 9, a, 3, 0.0, 0.0, kMaxLog, pre_a, out_a);
  BackgroundForward(c.data(), 9, b, 3, 0.0, 0.0, kMaxLog, pre_b, out_b);
  EXPECT_EQ(out_a[0], out_b[0]);        // the constant term alone in red
  EXPECT_GT(out_a[1], out_b[1] + 0.1);  // looking along +z sees the green term
  // The log-HDR model: HDR = exp(pre), LDR = sigmoid(pre + ln exposure + offset).
  double pre[3], out[6];
  BackgroundForward(c.data(), 1, a, 6, 0.5, -1.0, kMaxLog, pre, out);
  EXPECT_NEAR(out[3], std::exp(pre[0]), 1e-12);
  EXPECT_NEAR(out[0], 1.0 / (1.0 + std::exp(-(pre[0] - 1.0 + 0.5))), 1e-12);
  EXPECT_EQ(BackgroundBasisSize("fixed"), 0);
  EXPECT_EQ(BackgroundBasisSize("sky"), -1);
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
