#include "method/gaussian/sh4d.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using Vec = Eigen::VectorXd;
constexpr double kPi = std::numbers::pi;

// Central differences with h = 1e-5 in double. The colour is linear in the coefficients, so
// the only error is rounding (~1e-11 relative); 1e-6 still rejects any sign or factor slip.
constexpr hdr4d::testing::FdCheck kFd{1e-5, 1e-6};  // step, tolerance

Vec3<double> RandomDirection(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3<double>(n(rng), n(rng), n(rng)).normalized();
}

std::vector<double> ShValues(const Vec3<double>& d, int degree = 3) {
  std::vector<double> y((degree + 1) * (degree + 1));
  EvalShBasis<double>(d, degree, y.data());
  return y;
}

// Independent reference: orthonormal real SH from associated Legendre functions (no
// Condon-Shortley phase in P), times (-1)^m, the 3DGS sign convention, at index l^2 + l + m.
double ReferenceSh(int l, int m, const Vec3<double>& d) {
  const double z = d.z(), phi = std::atan2(d.y(), d.x());
  const int am = std::abs(m);
  // P_am^am = (2 am - 1)!! (1 - z^2)^(am/2), then the recurrence in l.
  double p_prev = 1.0;
  for (int i = 1; i <= am; ++i) p_prev *= (2 * i - 1) * std::sqrt(1 - z * z);
  double p = p_prev;
  if (l > am) {
    double p_cur = z * (2 * am + 1) * p_prev;
    for (int ll = am + 2; ll <= l; ++ll) {
      const double next = ((2 * ll - 1) * z * p_cur - (ll + am - 1) * p_prev) / (ll - am);
      p_prev = p_cur;
      p_cur = next;
    }
    p = p_cur;
  }
  double ratio = 1.0;  // (l - am)! / (l + am)!
  for (int i = l - am + 1; i <= l + am; ++i) ratio /= i;
  const double k = std::sqrt((2 * l + 1) / (4 * kPi) * ratio);
  double y = k * p;
  if (m > 0) y *= std::sqrt(2.0) * std::cos(m * phi);
  if (m < 0) y *= std::sqrt(2.0) * std::sin(am * phi);
  return (am % 2 ? -1.0 : 1.0) * y;
}

TEST(EvalShBasis, DcIsConstant) {
  std::mt19937 rng(1);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(ShValues(RandomDirection(rng))[0], kShC0Double);
    EXPECT_EQ(ShValues(RandomDirection(rng), 0)[0], kShC0Double);
  }
  EXPECT_DOUBLE_EQ(kShC0Double, 0.5 / std::sqrt(kPi));
}

TEST(EvalShBasis, ClosedFormAtAxes) {
  const std::vector<double> z = ShValues(Vec3<double>(0, 0, 1));
  const std::vector<double> x = ShValues(Vec3<double>(1, 0, 0));
  const std::vector<double> y = ShValues(Vec3<double>(0, 1, 0));
  std::vector<double> ez(16, 0.0), ex(16, 0.0), ey(16, 0.0);
  ez[0] = ex[0] = ey[0] = kShC0Double;
  ez[2] = kShC1;          // C1 z
  ez[6] = 2 * kShC2[2];   // C2[2] (2zz - xx - yy)
  ez[12] = 2 * kShC3[3];  // C3[3] z (2zz - 3xx - 3yy)
  ex[3] = -kShC1;         // -C1 x
  ex[6] = -kShC2[2];
  ex[8] = kShC2[4];    // C2[4] (xx - yy)
  ex[13] = -kShC3[4];  // C3[4] x (4zz - xx - yy)
  ex[15] = kShC3[6];   // C3[6] x (xx - 3yy)
  ey[1] = -kShC1;      // -C1 y
  ey[6] = -kShC2[2];
  ey[8] = -kShC2[4];
  ey[9] = -kShC3[0];   // C3[0] y (3xx - yy)
  ey[11] = -kShC3[2];  // C3[2] y (4zz - xx - yy)
  for (int i = 0; i < 16; ++i) {
    EXPECT_DOUBLE_EQ(z[i], ez[i]) << i;
    EXPECT_DOUBLE_EQ(x[i], ex[i]) << i;
    EXPECT_DOUBLE_EQ(y[i], ey[i]) << i;
  }
}

TEST(EvalShBasis, MatchesLegendreReference) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3<double> d = RandomDirection(rng);
    const std::vector<double> y = ShValues(d);
    for (int l = 0; l <= 3; ++l) {
      for (int m = -l; m <= l; ++m) {
        EXPECT_NEAR(y[l * l + l + m], ReferenceSh(l, m, d), 1e-13) << "l " << l << " m " << m;
      }
    }
  }
}

TEST(EvalShBasis, OrthonormalOnTheSphere) {
  // Gauss-Legendre (8 nodes) in z times 16 uniform angles in phi integrates every product of
  // two degree-3 harmonics exactly, so the Gram matrix must be the identity to rounding.
  const int n = 8;
  std::vector<double> nodes(n), weights(n);
  for (int i = 0; i < n; ++i) {
    double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 0;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1);
      const double step = p1 / dp;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    nodes[i] = x;
    weights[i] = 2 / ((1 - x * x) * dp * dp);
  }
  Eigen::Matrix<double, 16, 16> gram = Eigen::Matrix<double, 16, 16>::Zero();
  const int angles = 16;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < angles; ++j) {
      const double phi = 2 * kPi * (j + 0.3) / angles, r = std::sqrt(1 - nodes[i] * nodes[i]);
      const std::vector<double> y =
          ShValues(Vec3<double>(r * std::cos(phi), r * std::sin(phi), nodes[i]));
      const Eigen::Map<const Eigen::Matrix<double, 16, 1>> v(y.data());
      gram += weights[i] * (2 * kPi / angles) * v * v.transpose();
    }
  }
  EXPECT_LT((gram - Eigen::Matrix<double, 16, 16>::Identity()).cwiseAbs().maxCoeff(), 1e-13)
      << gram;
}

TEST(EvalColorBasisWeights, MasksInactiveDegrees) {
  const ColorBasis basis;  // 3, 2: 48 weights
  std::mt19937 rng(3);
  const Vec3<double> d = RandomDirection(rng);
  for (int sh = 0; sh <= 3; ++sh) {
    for (int td = 0; td <= 2; ++td) {
      std::vector<double> w(48, 7.0);
      EvalColorBasisWeights<double>(d, 0.13, 1.0, basis, sh, td, w.data());
      for (int k = 0; k < 48; ++k) {
        const bool active = k % 16 < (sh + 1) * (sh + 1) && k / 16 <= td;
        EXPECT_EQ(w[k] != 0.0, active) << k;
      }
    }
  }
}

TEST(EvalColorBasisWeights, TemporalCosines) {
  const ColorBasis basis;
  std::mt19937 rng(4);
  const Vec3<double> d = RandomDirection(rng);
  const std::vector<double> y = ShValues(d);
  const double duration = 2.5;
  auto weights = [&](double dt) {
    std::vector<double> w(48);
    EvalColorBasisWeights<double>(d, dt, duration, basis, 3, 2, w.data());
    return w;
  };
  const std::vector<double> w0 = weights(0.0), wp = weights(duration), wm = weights(-3 * duration);
  const std::vector<double> half = weights(duration / 2), quarter = weights(duration / 4);
  const std::vector<double> generic = weights(0.37);
  for (int lm = 0; lm < 16; ++lm) {
    for (int n = 0; n < 3; ++n) {
      EXPECT_EQ(w0[16 * n + lm], y[lm]);           // dt = 0: every block is Y
      EXPECT_NEAR(wp[16 * n + lm], y[lm], 1e-14);  // period T
      EXPECT_NEAR(wm[16 * n + lm], y[lm], 1e-14);
      EXPECT_NEAR(generic[16 * n + lm], y[lm] * std::cos(2 * kPi * n * 0.37 / duration), 1e-14);
    }
    EXPECT_NEAR(half[16 + lm], -y[lm], 1e-14);     // cos(pi)
    EXPECT_NEAR(half[32 + lm], y[lm], 1e-14);      // cos(2 pi)
    EXPECT_NEAR(quarter[16 + lm], 0.0, 1e-14);     // cos(pi / 2)
    EXPECT_NEAR(quarter[32 + lm], -y[lm], 1e-14);  // cos(pi)
  }
  // Symmetric in dt (cosines only).
  EXPECT_EQ(weights(0.4), weights(-0.4));
}

TEST(EvalColor4D, DtZeroSumsAllTemporalBlocks) {
  const ColorBasis basis;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  const int channels = 3;
  std::vector<double> coeffs(48 * channels);
  for (double& c : coeffs) c = n(rng);
  const Vec3<double> dir(0.3, -2.0, 1.1);
  const std::vector<double> y = ShValues(dir.normalized());
  double out[3];
  EvalColor4D<double>(coeffs.data(), basis, channels, dir, 0.0, 1.0, 3, 2, out);
  for (int c = 0; c < channels; ++c) {
    double expected = kColorOffset;
    for (int lm = 0; lm < 16; ++lm) {
      expected += y[lm] * (coeffs[lm * channels + c] + coeffs[(16 + lm) * channels + c] +
                           coeffs[(32 + lm) * channels + c]);
    }
    EXPECT_NEAR(out[c], expected, 1e-13);
  }
}

TEST(EvalColor4D, GoldenDcAndLinearTerm) {
  // DC coefficient 2 and the z coefficient (index 2) 3, looking along +z: 0.5 + 2 C0 + 3 C1.
  const ColorBasis basis;
  std::vector<double> coeffs(48, 0.0);
  coeffs[0] = 2;
  coeffs[2] = 3;
  double out;
  EvalColor4D<double>(coeffs.data(), basis, 1, Vec3<double>(0, 0, 5), 0.2, 1.0, 3, 2, &out);
  EXPECT_DOUBLE_EQ(out, 0.5 + 2 * kShC0Double + 3 * kShC1);
  // Degree 0 ignores the z coefficient; the direction length does not matter.
  EvalColor4D<double>(coeffs.data(), basis, 1, Vec3<double>(0, 0, 0.01), 0.2, 1.0, 0, 0, &out);
  EXPECT_DOUBLE_EQ(out, 0.5 + 2 * kShC0Double);
}

TEST(EvalColor4D, IgnoresInactiveCoefficients) {
  const ColorBasis basis;
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0.0, 1.0);
  const int channels = 6;
  const Vec3<double> dir = RandomDirection(rng);
  std::vector<double> coeffs(48 * channels), masked(48 * channels);
  for (int sh = 0; sh <= 3; ++sh) {
    for (int td = 0; td <= 2; ++td) {
      for (int k = 0; k < 48; ++k) {
        const bool active = k % 16 < (sh + 1) * (sh + 1) && k / 16 <= td;
        for (int c = 0; c < channels; ++c) {
          coeffs[k * channels + c] = active ? n(rng) : 1e6;
          masked[k * channels + c] = active ? coeffs[k * channels + c] : 0.0;
        }
      }
      double out[6], out_masked[6];
      EvalColor4D<double>(coeffs.data(), basis, channels, dir, 0.3, 1.0, sh, td, out);
      EvalColor4D<double>(masked.data(), basis, channels, dir, 0.3, 1.0, sh, td, out_masked);
      std::vector<double> w(48);
      EvalColorBasisWeights<double>(dir, 0.3, 1.0, basis, sh, td, w.data());
      for (int c = 0; c < channels; ++c) {
        double dot = kColorOffset;
        for (int k = 0; k < 48; ++k) dot += w[k] * masked[k * channels + c];
        EXPECT_EQ(out[c], out_masked[c]);
        EXPECT_NEAR(out[c], dot, 1e-13);
      }
      // Backward leaves the inactive gradients untouched (zero gradient).
      std::vector<double> grad(48 * channels, 0.0);
      const double dl[6] = {1, 2, 3, 4, 5, 6};
      EvalColor4DBackward<double>(coeffs.data(), basis, channels, dir, 0.3, 1.0, sh, td, dl,
                                  grad.data());
      for (int k = 0; k < 48; ++k) {
        const bool active = k % 16 < (sh + 1) * (sh + 1) && k / 16 <= td;
        for (int c = 0; c < channels; ++c) {
          EXPECT_DOUBLE_EQ(grad[k * channels + c], active ? w[k] * dl[c] : 0.0);
        }
      }
    }
  }
}

TEST(EvalColor4D, BackwardMatchesFiniteDifferencesAndAccumulates) {
  const ColorBasis basis;
  const int channels = 6;
  for (unsigned seed = 10; seed < 16; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    const int sh = static_cast<int>(seed % 4), td = static_cast<int>(seed % 3);
    const Vec3<double> dir(n(rng), n(rng), n(rng));
    const double dt = n(rng), duration = 1.7;
    std::vector<double> w_out(channels);
    for (double& v : w_out) v = n(rng);
    Vec x(48 * channels);
    for (int i = 0; i < x.size(); ++i) x(i) = n(rng);
    auto loss = [&](const Vec& v) {
      double out[6];
      EvalColor4D<double>(v.data(), basis, channels, dir, dt, duration, sh, td, out);
      double l = 0;
      for (int c = 0; c < channels; ++c) l += w_out[c] * out[c];
      return l;
    };
    Vec grad = Vec::Zero(x.size());
    EvalColor4DBackward<double>(x.data(), basis, channels, dir, dt, duration, sh, td, w_out.data(),
                                grad.data());
    kFd.ExpectMatch(grad, kFd.Gradient(loss, x));
    const Vec once = grad;
    EvalColor4DBackward<double>(x.data(), basis, channels, dir, dt, duration, sh, td, w_out.data(),
                                grad.data());
    EXPECT_TRUE(grad.isApprox(2 * once, 1e-15));
  }
}

TEST(EvalColor4D, StaticBasisLayoutAndFloat) {
  // 3D mode with SH degree 1: four coefficients per channel, no time blocks; dt is ignored.
  ColorBasis basis;
  basis.max_sh_degree = 1;
  basis.max_time_degree = 0;
  ASSERT_EQ(basis.coefficients(), 4);
  const float coeffs[4 * 2] = {1, -1, 0.5f, 0.25f, 2, 0, -3, 1};  // k * 2 + c
  float out[2];
  const Vec3<float> dir(3, 0, 4);  // d = (0.6, 0, 0.8)
  EvalColor4D<float>(coeffs, basis, 2, dir, 123.0f, 0.0f, 1, 0, out);
  const double c0 = kShC0Double, c1 = kShC1;
  EXPECT_NEAR(out[0], 0.5 + c0 * 1 + c1 * 0.8 * 2 - c1 * 0.6 * -3, 1e-6);
  EXPECT_NEAR(out[1], 0.5 + c0 * -1 + c1 * 0.8 * 0 - c1 * 0.6 * 1, 1e-6);
}

TEST(EvalColor4D, FloatMatchesDoubleAndZeroDirectionIsFinite) {
  const ColorBasis basis;
  std::mt19937 rng(20);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<double> cd(48 * 3);
  for (double& c : cd) c = n(rng);
  const std::vector<float> cf(cd.begin(), cd.end());
  const Vec3<double> dir(n(rng), n(rng), n(rng));
  double od[3];
  float of[3];
  EvalColor4D<double>(cd.data(), basis, 3, dir, 0.3, 1.0, 3, 2, od);
  EvalColor4D<float>(cf.data(), basis, 3, dir.cast<float>(), 0.3f, 1.0f, 3, 2, of);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(of[c], od[c], 1e-5);
  // A zero direction (Gaussian at the camera centre) keeps only the DC terms.
  EvalColor4D<float>(cf.data(), basis, 3, Vec3<float>::Zero(), 0.0f, 1.0f, 3, 2, of);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(of[c], 0.5 + kShC0Double * (cd[c] + cd[16 * 3 + c] + cd[32 * 3 + c]), 1e-5);
  }
}

TEST(EvalColorBasisWeightsDeathTest, RejectsBadDegrees) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");  // the core library may have started threads
  const ColorBasis basis;
  double w[48];
  const Vec3<double> d(0, 0, 1);
  EXPECT_DEATH(EvalColorBasisWeights<double>(d, 0.0, 1.0, basis, 4, 0, w), "sh_degree");
  EXPECT_DEATH(EvalColorBasisWeights<double>(d, 0.0, 1.0, basis, 0, 3, w), "time_degree");
  EXPECT_DEATH(EvalColorBasisWeights<double>(d, 0.0, 0.0, basis, 0, 1, w), "duration");
  ColorBasis big;
  big.max_time_degree = 3;
  EXPECT_DEATH(EvalColorBasisWeights<double>(d, 0.0, 1.0, big, 0, 0, w), "max_time_degree");
}

}  // namespace
}  // namespace hdr4d::method
