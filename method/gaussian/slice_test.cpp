#include "method/gaussian/slice.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <random>

#include "method/gaussian/rotation4d.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using Vec = Eigen::VectorXd;

// Central differences with h = 1e-5 in double: truncation and rounding are both ~1e-11 for the
// O(1) inputs used, so 1e-6 of the largest gradient component separates real errors (a sign or
// factor slip is ~1e0 of it) from noise with a wide margin.
constexpr hdr4d::testing::FdCheck kFd{1e-5, 1e-6};  // step, tolerance

template <typename T>
Vec4<T> RandomQuaternion(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec4<double>(n(rng), n(rng), n(rng), n(rng)).cast<T>();
}

// A 4D covariance with random rotation and the given log-scales.
template <typename T>
Mat4<T> RandomSigma(std::mt19937& rng, const Vec4<T>& log_scales) {
  const Vec4<T> ql = RandomQuaternion<T>(rng), qr = RandomQuaternion<T>(rng);
  return Covariance4D<T>(Rotation4D<T>(ql, qr), log_scales);
}

TEST(SliceAtTime, Golden) {
  Mat4<double> sigma;
  sigma << 2, 0, 0, 1,  //
      0, 1, 0, 0,       //
      0, 0, 1, 0,       //
      1, 0, 0, 4;
  const Slice<double> s = SliceAtTime<double>(Vec4<double>(1, 2, 3, 0.5), sigma, 1.5);
  EXPECT_DOUBLE_EQ(s.mean.x(), 1.25);  // 1 + 1 * (1.5 - 0.5) / 4
  EXPECT_DOUBLE_EQ(s.mean.y(), 2.0);
  EXPECT_DOUBLE_EQ(s.mean.z(), 3.0);
  Mat3<double> cov;
  cov << 1.75, 0, 0, 0, 1, 0, 0, 0, 1;  // 2 - 1 * 1 / 4
  EXPECT_EQ(s.cov, cov);
  EXPECT_DOUBLE_EQ(s.marginal, std::exp(-0.125));  // exp(-0.5 * 1 / 4)
}

TEST(SliceAtTime, MatchesPrecisionMatrixConditioning) {
  // Independent route: the conditional of a Gaussian has covariance (P_11)^-1 and mean
  // mu - (P_11)^-1 P_12 (t - mu_t), with P = Sigma^-1.
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat4<double> sigma = RandomSigma<double>(
        rng, Vec4<double>(0.5 * n(rng), 0.5 * n(rng), 0.5 * n(rng), 0.5 * n(rng)));
    const Vec4<double> mean(n(rng), n(rng), n(rng), n(rng));
    const double t = n(rng);
    const Mat4<double> P = sigma.inverse();
    const Mat3<double> cov = P.block<3, 3>(0, 0).inverse();
    const Vec3<double> m = mean.head<3>() - cov * P.block<3, 1>(0, 3) * (t - mean(3));
    const Slice<double> s = SliceAtTime<double>(mean, sigma, t);
    EXPECT_TRUE(s.cov.isApprox(cov, 1e-10));
    EXPECT_TRUE(s.mean.isApprox(m, 1e-10));
    EXPECT_EQ(s.cov, s.cov.transpose());  // exactly symmetric
  }
}

TEST(SliceAtTime, MarginalShape) {
  std::mt19937 rng(2);
  const Mat4<double> sigma = RandomSigma<double>(rng, Vec4<double>(0.1, -0.3, 0.2, -0.8));
  const Vec4<double> mean(0.1, 0.2, 0.3, 0.4);
  EXPECT_DOUBLE_EQ(SliceAtTime<double>(mean, sigma, 0.4).marginal, 1.0);
  const double sd = std::sqrt(sigma(3, 3));
  EXPECT_NEAR(SliceAtTime<double>(mean, sigma, 0.4 + sd).marginal, std::exp(-0.5), 1e-15);
  EXPECT_NEAR(SliceAtTime<double>(mean, sigma, 0.4 - 2 * sd).marginal, std::exp(-2.0), 1e-15);
  // At t = mu_t the slice is the marginal 3D Gaussian: mean mu_xyz.
  EXPECT_TRUE(SliceAtTime<double>(mean, sigma, 0.4).mean.isApprox(mean.head<3>(), 1e-15));
}

TEST(SliceAtTime, SpaceTimeIndependentGaussianIsUnchanged) {
  // q_l == q_r keeps the time axis separate: the slice is the spatial part at any t.
  std::mt19937 rng(3);
  const Vec4<double> q = RandomQuaternion<double>(rng);
  const Mat4<double> sigma =
      Covariance4D<double>(Rotation4D<double>(q, q), Vec4<double>(0.2, -0.5, 0.1, 0.3));
  const Vec4<double> mean(1, -2, 3, 0.25);
  const Slice<double> s = SliceAtTime<double>(mean, sigma, 0.9);
  EXPECT_TRUE(s.mean.isApprox(mean.head<3>(), 1e-14));
  EXPECT_TRUE(s.cov.isApprox(sigma.block<3, 3>(0, 0), 1e-14));
}

TEST(SliceAtTime, BackwardMatchesFiniteDifferences) {
  for (unsigned seed = 10; seed < 18; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    const Mat4<double> sigma0 = RandomSigma<double>(
        rng, Vec4<double>(0.4 * n(rng), 0.4 * n(rng), 0.4 * n(rng), 0.4 * n(rng)));
    const Vec4<double> mean0(n(rng), n(rng), n(rng), n(rng));
    const double t = mean0(3) + 0.8 * n(rng) * std::sqrt(sigma0(3, 3));
    const Vec3<double> wm(n(rng), n(rng), n(rng));
    Mat3<double> wc;
    for (int i = 0; i < 9; ++i) wc(i) = n(rng);  // general, not symmetric
    const double wp = n(rng);
    Vec x(20);
    x << mean0, Eigen::Map<const Vec>(sigma0.data(), 16);
    auto loss = [&](const Vec& v) {
      const Mat4<double> sigma = Eigen::Map<const Mat4<double>>(v.data() + 4);
      const Slice<double> s = SliceAtTime<double>(v.head<4>(), sigma, t);
      return wm.dot(s.mean) + wc.cwiseProduct(s.cov).sum() + wp * s.marginal;
    };
    Vec4<double> dmean;
    Mat4<double> dsigma;
    SliceAtTimeBackward<double>(mean0, sigma0, t, wm, wc, wp, &dmean, &dsigma);
    EXPECT_EQ((dsigma.block<1, 3>(3, 0)), (Eigen::RowVector3d::Zero()));  // not read
    Vec analytic(20);
    analytic << dmean, Eigen::Map<const Vec>(dsigma.data(), 16);
    kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));
  }
}

TEST(SliceAtTime, DegenerateScalesStayFinite) {
  // Float, scales spanning exp(-12)..exp(4) per axis and random rotations: needles in space-time
  // whose time variance is tiny, huge, or almost the whole variance.
  std::mt19937 rng(20);
  std::uniform_real_distribution<float> log_scale(-12.0f, 4.0f);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  std::normal_distribution<float> n(0.0f, 1.0f);
  int visible = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec4<float> ls(log_scale(rng), log_scale(rng), log_scale(rng), log_scale(rng));
    if (trial % 4 == 1) ls = Vec4<float>(4, 4, -12, -12);    // nearly degenerate axes
    if (trial % 4 == 2) ls = Vec4<float>(-12, -12, -12, 4);  // a pure time needle
    const Mat4<float> sigma = RandomSigma<float>(rng, ls);
    const Vec4<float> mean(u(rng), u(rng), u(rng), u(rng));
    const float t = trial % 4 == 3 ? mean(3) : u(rng);
    const Slice<float> s = SliceAtTime<float>(mean, sigma, t);
    ASSERT_TRUE(s.mean.allFinite() && s.cov.allFinite())
        << "trial " << trial << " ls " << ls.transpose();
    ASSERT_TRUE(s.marginal >= 0.0f && s.marginal <= 1.0f);
    visible += TemporallyVisible(s.marginal);
    Vec4<float> dmean;
    Mat4<float> dsigma;
    Mat3<float> gc;
    for (int i = 0; i < 9; ++i) gc(i) = n(rng);
    SliceAtTimeBackward<float>(mean, sigma, t, Vec3<float>(n(rng), n(rng), n(rng)), gc, n(rng),
                               &dmean, &dsigma);
    ASSERT_TRUE(dmean.allFinite() && dsigma.allFinite()) << "trial " << trial;
  }
  EXPECT_GT(visible, 400);  // the sample does exercise live Gaussians, not only culled ones
}

TEST(SliceAtTime, ZeroTimeVarianceUsesFloor) {
  // Sigma_tt = 0 exactly (and an all-zero Sigma): the floor replaces it, no NaN/Inf, and no
  // gradient reaches the floored Sigma_tt.
  for (const float scale : {1.0f, 0.0f}) {
    Mat4<float> sigma = Mat4<float>::Zero();
    sigma.block<3, 3>(0, 0) = scale * Mat3<float>::Identity();
    const Vec4<float> mean(1, 2, 3, 0.5f);
    for (const float t : {0.5f, 0.6f, 3.0f}) {
      const Slice<float> s = SliceAtTime<float>(mean, sigma, t);
      EXPECT_EQ(s.mean, mean.head<3>());
      EXPECT_EQ(s.cov, (sigma.block<3, 3>(0, 0)));
      EXPECT_EQ(s.marginal, t == 0.5f ? 1.0f : 0.0f);
      Vec4<float> dmean;
      Mat4<float> dsigma;
      SliceAtTimeBackward<float>(mean, sigma, t, Vec3<float>(1, -2, 3), Mat3<float>::Ones(), 1.0f,
                                 &dmean, &dsigma);
      EXPECT_TRUE(dmean.allFinite() && dsigma.allFinite()) << dsigma;
      EXPECT_EQ(dsigma(3, 3), 0.0f);
      EXPECT_EQ((dmean.head<3>()), Vec3<float>(1, -2, 3));
    }
  }
}

TEST(TemporallyVisible, CullsAtOrBelowFivePercent) {
  EXPECT_FALSE(TemporallyVisible(0.0f));
  EXPECT_FALSE(TemporallyVisible(0.05f));
  EXPECT_TRUE(TemporallyVisible(std::nextafter(0.05f, 1.0f)));
  EXPECT_TRUE(TemporallyVisible(1.0));
  EXPECT_FALSE(TemporallyVisible(0.049));
  // p(t) = 0.05 is |t - mu_t| = sqrt(2 ln 20) standard deviations.
  Mat4<double> sigma = Mat4<double>::Identity();
  const double edge = std::sqrt(2 * std::log(20.0));
  EXPECT_TRUE(
      TemporallyVisible(SliceAtTime<double>(Vec4<double>::Zero(), sigma, 0.999 * edge).marginal));
  EXPECT_FALSE(
      TemporallyVisible(SliceAtTime<double>(Vec4<double>::Zero(), sigma, 1.001 * edge).marginal));
}

}  // namespace
}  // namespace hdr4d::method
