#include "method/gaussian/rotation4d.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>

#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using Vec = Eigen::VectorXd;

// Central differences with h = 1e-5 in double: truncation h^2 f'''/6 and rounding eps |f| / h
// are both about 1e-11 for the O(1) functions tested here, so a mismatch above 1e-6 of the
// gradient's largest component is a real error (a sign or factor-2 slip is ~1e0 of it).
constexpr hdr4d::testing::FdCheck kFd{1e-5, 1e-6};  // step, tolerance

Vec4<double> RandomQuaternion(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec4<double> q(n(rng), n(rng), n(rng), n(rng));
  return scale * q.normalized();
}

Mat4<double> RandomMatrix4(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Mat4<double> m;
  for (int i = 0; i < 16; ++i) m(i) = n(rng);
  return m;
}

// Reverses the order of x, y, z.
Mat3<double> ReverseAxes(const Mat3<double>& m) { return m.reverse(); }

TEST(Rotation4D, IdentityQuaternionsGiveIdentity) {
  const Vec4<double> id(1, 0, 0, 0);
  EXPECT_EQ(Rotation4D(id, id), (Mat4<double>::Identity()));
  EXPECT_EQ(Rotation4D<float>(Vec4<float>(3, 0, 0, 0), Vec4<float>(0.5f, 0, 0, 0)),
            (Mat4<float>::Identity()));
}

TEST(Rotation4D, GoldenRightQuaternionMixesZAndTime) {
  // q_l = 1, q_r = i: A = M_r(0,1,0,0) = [[0,1,0,0],[-1,0,0,0],[0,0,0,-1],[0,0,1,0]], and its
  // flip happens to be the same matrix. Raw norms 2 and 0.5 test the normalisation.
  Mat4<double> expected;
  expected << 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0;
  EXPECT_TRUE(
      Rotation4D(Vec4<double>(2, 0, 0, 0), Vec4<double>(0, 0.5, 0, 0)).isApprox(expected, 1e-15));
  // q_l = (1,1,0,0)/sqrt2, q_r = 1: A = M_l = [[1,-1,0,0],[1,1,0,0],[0,0,1,-1],[0,0,1,1]]/sqrt2;
  // here the flip R(i,j) = A(3-i,3-j) matters (it gives A^T).
  Mat4<double> expected_l;
  expected_l << 1, 1, 0, 0, -1, 1, 0, 0, 0, 0, 1, 1, 0, 0, -1, 1;
  expected_l /= std::sqrt(2.0);
  const Mat4<double> R = Rotation4D(Vec4<double>(1, 1, 0, 0), Vec4<double>(1, 0, 0, 0));
  EXPECT_TRUE(R.isApprox(expected_l, 1e-15)) << R;
}

TEST(Rotation4D, IsOrthonormalWithUnitDeterminant) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    const Mat4<double> R = Rotation4D(RandomQuaternion(rng, 0.3 + trial * 0.1),
                                      RandomQuaternion(rng, 2.0 - trial * 0.03));
    EXPECT_TRUE((R * R.transpose()).isApprox(Mat4<double>::Identity(), 1e-14));
    EXPECT_NEAR(R.determinant(), 1.0, 1e-13);
  }
}

TEST(Rotation4D, FloatMatchesDouble) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 10; ++trial) {
    const Vec4<double> ql = RandomQuaternion(rng, 1.5), qr = RandomQuaternion(rng, 0.7);
    const Mat4<double> Rd = Rotation4D(ql, qr);
    const Mat4<float> Rf = Rotation4D<float>(ql.cast<float>(), qr.cast<float>());
    EXPECT_LT((Rf.cast<double>() - Rd).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(Rotation4D, EqualQuaternionsRotateSpaceOnly) {
  // A = M_l(q) M_r(q) is v -> q v q*, which fixes the real axis; the flip moves that axis to
  // index 3 (time) and reverses x, y, z, so the spatial block is the 3DGS rotation of q with
  // its axes reversed.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec4<double> q = RandomQuaternion(rng, 1.3);
    const Mat4<double> R = Rotation4D(q, Vec4<double>(2.0 * q));
    EXPECT_NEAR(R(3, 3), 1.0, 1e-15);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(R(3, i), 0.0, 1e-15);
      EXPECT_NEAR(R(i, 3), 0.0, 1e-15);
    }
    const Mat3<double> spatial = R.block<3, 3>(0, 0);
    EXPECT_TRUE(spatial.isApprox(ReverseAxes(Rotation3D(q)), 1e-14));
    // Distinct quaternions do couple space and time.
    const Mat4<double> mixed = Rotation4D(q, RandomQuaternion(rng, 1.0));
    EXPECT_GT((mixed.block<3, 1>(0, 3).norm()), 1e-3);
  }
}

TEST(Rotation4D, NormalisesRawQuaternions) {
  std::mt19937 rng(4);
  const Vec4<double> ql = RandomQuaternion(rng, 1.0), qr = RandomQuaternion(rng, 1.0);
  EXPECT_TRUE(Rotation4D(ql, qr).isApprox(
      Rotation4D(Vec4<double>(3.7 * ql), Vec4<double>(0.01 * qr)), 1e-14));
}

TEST(Rotation4D, ZeroQuaternionIsIdentityWithoutNaN) {
  std::mt19937 rng(5);
  const Vec4<double> qr = RandomQuaternion(rng, 1.0);
  const Vec4<double> zero = Vec4<double>::Zero();
  EXPECT_TRUE(Rotation4D(zero, qr).isApprox(Rotation4D(Vec4<double>(1, 0, 0, 0), qr), 1e-15));
  EXPECT_EQ(Rotation4D(zero, zero), (Mat4<double>::Identity()));
  EXPECT_EQ(Rotation4D<float>(Vec4<float>::Zero(), Vec4<float>::Zero()), (Mat4<float>::Identity()));
  Vec4<double> gl, gr;
  Rotation4DBackward(zero, qr, RandomMatrix4(rng), &gl, &gr);
  EXPECT_EQ(gl, (Vec4<double>::Zero()));
  EXPECT_TRUE(gr.allFinite());
  EXPECT_GT(gr.norm(), 0.0);
}

TEST(Rotation4D, BackwardMatchesFiniteDifferences) {
  for (unsigned seed = 10; seed < 16; ++seed) {
    std::mt19937 rng(seed);
    const Mat4<double> W = RandomMatrix4(rng);  // L = <W, R>, so dL/dR = W
    Vec x(8);
    x << RandomQuaternion(rng, 0.5 + 0.3 * (seed - 10)), RandomQuaternion(rng, 1.7);
    auto loss = [&](const Vec& v) {
      return W.cwiseProduct(Rotation4D(Vec4<double>(v.head<4>()), Vec4<double>(v.tail<4>()))).sum();
    };
    Vec4<double> gl, gr;
    Rotation4DBackward(Vec4<double>(x.head<4>()), Vec4<double>(x.tail<4>()), W, &gl, &gr);
    Vec analytic(8);
    analytic << gl, gr;
    kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));
  }
}

TEST(Covariance4D, GoldenAxisAlignedAndEigenstructure) {
  const Vec4<double> ls(0.1, -0.7, 0.4, -2.0);
  const Mat4<double> S = Covariance4D(Mat4<double>(Mat4<double>::Identity()), ls);
  EXPECT_TRUE(S.isApprox(Mat4<double>((2 * ls).array().exp().matrix().asDiagonal()), 1e-15));

  std::mt19937 rng(20);
  const Mat4<double> R = Rotation4D(RandomQuaternion(rng, 1), RandomQuaternion(rng, 1));
  const Mat4<double> sigma = Covariance4D(R, ls);
  EXPECT_TRUE(sigma.isApprox(sigma.transpose(), 1e-15));
  for (int k = 0; k < 4; ++k) {  // the columns of R are the principal axes
    EXPECT_TRUE((sigma * R.col(k)).isApprox(std::exp(2 * ls(k)) * R.col(k), 1e-13));
  }
}

TEST(Covariance4D, BackwardMatchesFiniteDifferences) {
  for (unsigned seed = 30; seed < 35; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    const Mat4<double> W = RandomMatrix4(rng);  // general, not symmetric
    // R need not be orthonormal for the formula; a general matrix tests more of it.
    Vec x(20);
    for (int i = 0; i < 16; ++i) x(i) = n(rng);
    for (int i = 16; i < 20; ++i) x(i) = 0.5 * n(rng);
    auto unpack_r = [](const Vec& v) {
      return Mat4<double>(Eigen::Map<const Mat4<double>>(v.data()));
    };
    auto loss = [&](const Vec& v) {
      return W.cwiseProduct(Covariance4D(unpack_r(v), Vec4<double>(v.tail<4>()))).sum();
    };
    Mat4<double> dR;
    Vec4<double> dls;
    Covariance4DBackward(unpack_r(x), Vec4<double>(x.tail<4>()), W, &dR, &dls);
    Vec analytic(20);
    analytic << Eigen::Map<const Vec>(dR.data(), 16), dls;
    kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));
  }
}

TEST(Rotation3D, MatchesEigenQuaternionAndGolden) {
  const double theta = 0.8;
  Mat3<double> rz;
  rz << std::cos(theta), -std::sin(theta), 0, std::sin(theta), std::cos(theta), 0, 0, 0, 1;
  EXPECT_TRUE(Rotation3D(Vec4<double>(2 * std::cos(theta / 2), 0, 0, 2 * std::sin(theta / 2)))
                  .isApprox(rz, 1e-15));
  std::mt19937 rng(40);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec4<double> q = RandomQuaternion(rng, 0.4 + trial);
    const Eigen::Quaterniond eq(q(0), q(1), q(2), q(3));
    const Mat3<double> R = Rotation3D(q);
    EXPECT_TRUE(R.isApprox(eq.normalized().toRotationMatrix(), 1e-14));
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  }
  EXPECT_EQ(Rotation3D<double>(Vec4<double>::Zero()), (Mat3<double>::Identity()));
}

TEST(Rotation3D, BackwardMatchesFiniteDifferences) {
  for (unsigned seed = 50; seed < 56; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    Mat3<double> W;
    for (int i = 0; i < 9; ++i) W(i) = n(rng);
    const Vec x = RandomQuaternion(rng, 0.6 + 0.2 * (seed - 50));
    auto loss = [&](const Vec& v) { return W.cwiseProduct(Rotation3D(Vec4<double>(v))).sum(); };
    Vec4<double> g;
    Rotation3DBackward(Vec4<double>(x), W, &g);
    kFd.ExpectMatch(g, kFd.Gradient(loss, x));
  }
  Vec4<double> g;
  Rotation3DBackward<double>(Vec4<double>::Zero(), Mat3<double>::Ones(), &g);
  EXPECT_EQ(g, (Vec4<double>::Zero()));
}

TEST(Covariance3D, ForwardAndBackward) {
  const Vec3<double> ls(0.3, -1.2, 0.05);
  std::mt19937 rng(60);
  const Mat3<double> R = Rotation3D(RandomQuaternion(rng, 1));
  const Mat3<double> sigma = Covariance3D(R, ls);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE((sigma * R.col(k)).isApprox(std::exp(2 * ls(k)) * R.col(k), 1e-13));
  }
  for (unsigned seed = 61; seed < 65; ++seed) {
    std::mt19937 r2(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    Mat3<double> W;
    for (int i = 0; i < 9; ++i) W(i) = n(r2);
    Vec x(12);
    for (int i = 0; i < 12; ++i) x(i) = (i < 9 ? 1.0 : 0.5) * n(r2);
    auto unpack_r = [](const Vec& v) {
      return Mat3<double>(Eigen::Map<const Mat3<double>>(v.data()));
    };
    auto loss = [&](const Vec& v) {
      return W.cwiseProduct(Covariance3D(unpack_r(v), Vec3<double>(v.tail<3>()))).sum();
    };
    Mat3<double> dR;
    Vec3<double> dls;
    Covariance3DBackward(unpack_r(x), Vec3<double>(x.tail<3>()), W, &dR, &dls);
    Vec analytic(12);
    analytic << Eigen::Map<const Vec>(dR.data(), 9), dls;
    kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));
  }
}

TEST(Covariance4D, ChainedWithRotationMatchesFiniteDifferences) {
  // Sigma(q_l, q_r, s) end to end: the two backwards compose under the gradient convention.
  for (unsigned seed = 70; seed < 74; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    const Mat4<double> W = RandomMatrix4(rng);
    Vec x(12);
    x << RandomQuaternion(rng, 1.1), RandomQuaternion(rng, 0.9), 0.4 * n(rng), 0.4 * n(rng),
        0.4 * n(rng), 0.4 * n(rng);
    auto loss = [&](const Vec& v) {
      const Mat4<double> R =
          Rotation4D(Vec4<double>(v.segment<4>(0)), Vec4<double>(v.segment<4>(4)));
      return W.cwiseProduct(Covariance4D(R, Vec4<double>(v.segment<4>(8)))).sum();
    };
    const Vec4<double> ql = x.segment<4>(0), qr = x.segment<4>(4), ls = x.segment<4>(8);
    Mat4<double> dR;
    Vec4<double> dls, gl, gr;
    Covariance4DBackward(Rotation4D(ql, qr), ls, W, &dR, &dls);
    Rotation4DBackward(ql, qr, dR, &gl, &gr);
    Vec analytic(12);
    analytic << gl, gr, dls;
    kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));
  }
}

// The two building blocks every rotation/covariance backward uses, checked on their own.
TEST(RotationDetail, NormalizeQuaternionBackwardMatchesFiniteDifferences) {
  std::mt19937 rng(21);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 5; ++trial) {
    Vec4<double> q, w;
    for (int k = 0; k < 4; ++k) q[k] = n01(rng), w[k] = n01(rng);
    auto f = [&](const Vec& x) { return w.dot(detail::NormalizeQuaternion(Vec4<double>(x))); };
    const Vec4<double> analytic = detail::NormalizeQuaternionBackward(q, w);
    kFd.ExpectMatch(Vec(analytic), kFd.Gradient(f, Vec(q)));
  }
}

TEST(RotationDetail, CovarianceFromRotationBackwardMatchesFiniteDifferences) {
  std::mt19937 rng(22);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 4; ++trial) {
    Eigen::Matrix<double, 3, 3> R, G;
    Eigen::Matrix<double, 3, 1> s;
    for (int k = 0; k < 9; ++k) R(k) = n01(rng), G(k) = n01(rng);  // any R: the formula is general
    for (int k = 0; k < 3; ++k) s[k] = 0.3 * n01(rng);
    auto loss = [&](const Eigen::Matrix<double, 3, 3>& r, const Eigen::Matrix<double, 3, 1>& ls) {
      return (G.array() * detail::CovarianceFromRotation<double, 3>(r, ls).array()).sum();
    };
    Eigen::Matrix<double, 3, 3> dR;
    Eigen::Matrix<double, 3, 1> ds;
    detail::CovarianceFromRotationBackward<double, 3>(R, s, G, &dR, &ds);
    Vec x(12), analytic(12);
    for (int k = 0; k < 9; ++k) x[k] = R(k), analytic[k] = dR(k);
    for (int k = 0; k < 3; ++k) x[9 + k] = s[k], analytic[9 + k] = ds[k];
    auto f = [&](const Vec& v) {
      Eigen::Matrix<double, 3, 3> r;
      Eigen::Matrix<double, 3, 1> ls;
      for (int k = 0; k < 9; ++k) r(k) = v[k];
      for (int k = 0; k < 3; ++k) ls[k] = v[9 + k];
      return loss(r, ls);
    };
    kFd.ExpectMatch(analytic, kFd.Gradient(f, x));
  }
}

}  // namespace
}  // namespace hdr4d::method
