#include "method/gaussian/projection.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <random>

#include "core/geometry/camera.h"
#include "method/gaussian/rotation4d.h"
#include "method/gaussian/slice.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using Vec = Eigen::VectorXd;

// Central differences with h = 1e-6 in double. Inputs are scaled so that every quantity varies
// on scales >= 0.05 (world units, covariance entries), so truncation (h / 0.05)^2 ~ 4e-10 and
// rounding eps |L| / h ~ 1e-10 stay far below the 1e-6 tolerance (relative to the largest
// gradient component), while a sign or factor slip is of order 1 of it.
constexpr hdr4d::testing::FdCheck kFd{1e-6, 1e-6};  // step, tolerance

Vec4<double> RandomQuaternion(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec4<double>(n(rng), n(rng), n(rng), n(rng));
}

ViewParams<double> SimpleView() {
  ViewParams<double> v;
  v.rotation.setIdentity();
  v.translation.setZero();
  v.fx = v.fy = 100;
  v.cx = 50;
  v.cy = 40;
  v.width = 100;
  v.height = 80;
  return v;
}

// A random camera with fx ~ 60..90 for a 100x80 image; the world point of camera-space p.
ViewParams<double> RandomView(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ViewParams<double> v;
  v.rotation = Rotation3D(RandomQuaternion(rng));
  v.translation = Vec3<double>(u(rng), u(rng), u(rng));
  v.fx = 75 + 15 * u(rng);
  v.fy = 75 + 15 * u(rng);
  v.cx = 50 + 5 * u(rng);
  v.cy = 40 + 5 * u(rng);
  v.width = 100;
  v.height = 80;
  return v;
}
Vec3<double> WorldFromCamera(const ViewParams<double>& v, const Vec3<double>& p) {
  return v.rotation.transpose() * (p - v.translation);
}

// Covariance with random axes and the given standard deviations.
Mat3<double> RandomCov(std::mt19937& rng, const Vec3<double>& sd) {
  const Mat3<double> R = Rotation3D(RandomQuaternion(rng));
  return R * sd.array().square().matrix().asDiagonal() * R.transpose();
}

// L = wm . mean2d + wc . conic over (mean3, cov3 entries), analytic and numeric gradients.
void CheckProjectionGradient(const ViewParams<double>& view,
                             const Vec3<double>& mean3,
                             const Mat3<double>& cov3,
                             std::mt19937& rng,
                             double h = 0) {
  std::normal_distribution<double> n(0.0, 1.0);
  // The mean's pixel gradient is ~fx/z larger than the rest; 1/fx balances the two terms.
  const Vec2<double> wm = Vec2<double>(n(rng), n(rng)) / view.fx;
  const Vec3<double> wc(n(rng), n(rng), n(rng));
  ASSERT_TRUE(ProjectEwa(mean3, cov3, view).visible);
  Vec x(12);
  x << mean3, Eigen::Map<const Vec>(cov3.data(), 9);
  auto loss = [&](const Vec& v) {
    const Splat2D<double> s =
        ProjectEwa<double>(v.head<3>(), Eigen::Map<const Mat3<double>>(v.data() + 3), view);
    return wm.dot(s.mean) + wc.dot(s.conic);
  };
  Vec3<double> dmean;
  Mat3<double> dcov;
  ProjectEwaBackward(mean3, cov3, view, wm, wc, &dmean, &dcov);
  Vec analytic(12);
  analytic << dmean, Eigen::Map<const Vec>(dcov.data(), 9);
  kFd.ExpectMatch(analytic, kFd.Gradient(loss, x, h));
}

TEST(ProjectEwa, Golden) {
  // p = (0.5, -0.25, 2), cov3 = 0.01 I: J = [[50, 0, -12.5], [0, 50, 6.25]], so
  // J J^T 0.01 = [[26.5625, -0.78125], [-0.78125, 25.390625]]; plus the dilation (the float
  // constant 0.3f, also in double) on the diagonal.
  const Splat2D<double> s = ProjectEwa<double>(Vec3<double>(0.5, -0.25, 2),
                                               0.01 * Mat3<double>::Identity(), SimpleView());
  ASSERT_TRUE(s.visible);
  EXPECT_DOUBLE_EQ(s.mean.x(), 75.0);  // 100 * 0.25 + 50
  EXPECT_DOUBLE_EQ(s.mean.y(), 27.5);  // 100 * -0.125 + 40
  EXPECT_DOUBLE_EQ(s.depth, 2.0);
  const double dilation = kCov2dDilation;
  const double a = 26.5625 + dilation, b = -0.78125, c = 25.390625 + dilation;
  EXPECT_NEAR(s.cov2d(0), a, 1e-12);
  EXPECT_NEAR(s.cov2d(1), b, 1e-12);
  EXPECT_NEAR(s.cov2d(2), c, 1e-12);
  const double det = a * c - b * b;
  EXPECT_NEAR(s.conic(0), c / det, 1e-15);
  EXPECT_NEAR(s.conic(1), -b / det, 1e-15);
  EXPECT_NEAR(s.conic(2), a / det, 1e-15);
  EXPECT_EQ(s.radius, 16);  // ceil(3 sqrt(27.253125)) = ceil(15.66)

  // A point Gaussian keeps only the dilation: lambda_max = 0.3 + sqrt(0.1), radius ceil(2.36).
  const Splat2D<double> dot =
      ProjectEwa<double>(Vec3<double>(0, 0, 5), Mat3<double>::Zero(), SimpleView());
  ASSERT_TRUE(dot.visible);
  EXPECT_EQ(dot.radius, 3);
  EXPECT_EQ(dot.cov2d, Vec3<double>(dilation, 0, dilation));
}

TEST(ProjectEwa, ConicInvertsCovariance) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const ViewParams<double> view = RandomView(rng);
    const Vec3<double> mean = WorldFromCamera(view, Vec3<double>(0.2, -0.1, 2.0 + trial * 0.1));
    const Splat2D<double> s = ProjectEwa(mean, RandomCov(rng, Vec3<double>(0.1, 0.2, 0.05)), view);
    ASSERT_TRUE(s.visible);
    Mat2<double> cov, conic;
    cov << s.cov2d(0), s.cov2d(1), s.cov2d(1), s.cov2d(2);
    conic << s.conic(0), s.conic(1), s.conic(1), s.conic(2);
    EXPECT_TRUE((cov * conic).isApprox(Mat2<double>::Identity(), 1e-12));
  }
}

TEST(ProjectEwa, MatchesCameraProjectFromCamera) {
  // ViewParams::FromCamera must use the same axes and pixel convention as core/geometry/camera.h.
  Camera camera;
  camera.intrinsics = PinholeIntrinsics::FromFovX(0.9, 120, 90);
  camera.world_from_cam_gl =
      LookAtWorldFromCamGl(Eigen::Vector3d(3, 1, 2), Eigen::Vector3d(0, 0, 0));
  const ViewParams<double> view = ViewParams<double>::FromCamera(camera);
  EXPECT_TRUE(view.Center().isApprox(camera.Center(), 1e-14));
  EXPECT_NEAR(view.TanFovX(), std::tan(0.45), 1e-14);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int trial = 0; trial < 10; ++trial) {
    const Vec3<double> point(u(rng), u(rng), u(rng));
    const auto expected = camera.Project(point);
    ASSERT_TRUE(expected.has_value());
    const Splat2D<double> s =
        ProjectEwa(point, Mat3<double>(0.01 * Mat3<double>::Identity()), view);
    ASSERT_TRUE(s.visible);
    EXPECT_NEAR(s.mean.x(), expected->x(), 1e-10);
    EXPECT_NEAR(s.mean.y(), expected->y(), 1e-10);
    EXPECT_NEAR(s.depth, expected->z(), 1e-12);
  }
  const ViewParams<float> viewf = ViewParams<float>::FromCamera(camera);
  EXPECT_EQ(viewf.width, 120);
  EXPECT_FLOAT_EQ(viewf.fx, static_cast<float>(camera.intrinsics.fx));
}

TEST(ProjectEwa, NearPlaneAndDegenerateCovarianceAreInvisible) {
  const ViewParams<double> view = SimpleView();
  const Mat3<double> cov = 0.01 * Mat3<double>::Identity();
  EXPECT_FALSE(ProjectEwa<double>(Vec3<double>(0, 0, 0.19), cov, view).visible);
  EXPECT_FALSE(ProjectEwa<double>(Vec3<double>(0, 0, kNearPlane), cov, view).visible);
  EXPECT_FALSE(ProjectEwa<double>(Vec3<double>(0, 0, -3), cov, view).visible);
  EXPECT_TRUE(ProjectEwa<double>(Vec3<double>(0, 0, 0.21), cov, view).visible);
  // Not positive semi-definite: det <= 0 (indefinite), or negative-definite with det > 0 but
  // no positive eigenvalue (radius 0; 3DGS would take the sqrt of a negative number).
  const Mat3<double> indefinite = Vec3<double>(-1, 1, 0).asDiagonal();
  const Mat3<double> negative = Vec3<double>(-1, -1, 0).asDiagonal();
  for (const Mat3<double>& bad : {indefinite, negative}) {
    const Splat2D<double> s = ProjectEwa<double>(Vec3<double>(0.1, 0.1, 2), bad, view);
    EXPECT_FALSE(s.visible);
    Vec3<double> dmean;
    Mat3<double> dcov;
    ProjectEwaBackward<double>(Vec3<double>(0.1, 0.1, 2), bad, view, Vec2<double>(1, 1),
                               Vec3<double>(1, 1, 1), &dmean, &dcov);
    EXPECT_EQ(dmean, (Vec3<double>::Zero()));
    EXPECT_EQ(dcov, (Mat3<double>::Zero()));
  }
  Vec3<double> dmean;
  Mat3<double> dcov;
  ProjectEwaBackward<double>(Vec3<double>(0, 0, 0.1), cov, view, Vec2<double>(1, 1),
                             Vec3<double>(1, 1, 1), &dmean, &dcov);
  EXPECT_EQ(dmean, (Vec3<double>::Zero()));
}

TEST(ProjectEwa, JacobianIsClampedOutsideTheGuardBand) {
  // Beyond 1.3 tan(fov/2) the footprint stops growing: two points at the same depth but
  // different far-off-screen x get the same 2D covariance; inside the band it differs.
  const ViewParams<double> view = SimpleView();  // tan_fovx = 0.5, guard band x/z = 0.65
  std::mt19937 rng(3);
  const Mat3<double> cov = RandomCov(rng, Vec3<double>(0.1, 0.3, 0.2));
  const Splat2D<double> far1 = ProjectEwa<double>(Vec3<double>(2 * 0.7, 0.1, 2), cov, view);
  const Splat2D<double> far2 = ProjectEwa<double>(Vec3<double>(2 * 3.0, 0.1, 2), cov, view);
  const Splat2D<double> edge = ProjectEwa<double>(Vec3<double>(2 * 0.65, 0.1, 2), cov, view);
  const Splat2D<double> in = ProjectEwa<double>(Vec3<double>(2 * 0.6, 0.1, 2), cov, view);
  EXPECT_TRUE(far1.cov2d.isApprox(far2.cov2d, 1e-14));
  EXPECT_TRUE(far1.cov2d.isApprox(edge.cov2d, 1e-14));
  EXPECT_FALSE(in.cov2d.isApprox(edge.cov2d, 1e-6));
  EXPECT_NE(far1.mean.x(), far2.mean.x());  // the mean itself is not clamped
}

TEST(ProjectEwa, BackwardMatchesFiniteDifferences) {
  for (unsigned seed = 10; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const ViewParams<double> view = RandomView(rng);
    const double z = 1.5 + 1.5 * (u(rng) + 1);
    const Vec3<double> p(0.4 * z * u(rng), 0.4 * z * u(rng), z);
    const Mat3<double> cov =
        RandomCov(rng, Vec3<double>(0.1 + 0.1 * (u(rng) + 1), 0.3, 0.05 + 0.05 * (u(rng) + 1)));
    SCOPED_TRACE(seed);
    CheckProjectionGradient(view, WorldFromCamera(view, p), cov, rng);
  }
}

TEST(ProjectEwa, BackwardNearTheClampOnBothSides) {
  // x/z and y/z 3% inside and outside the guard band (the FD step moves them by ~1e-6).
  std::mt19937 rng(30);
  const ViewParams<double> view = RandomView(rng);
  const double lim_x = kFrustumTanMargin * view.TanFovX(),
               lim_y = kFrustumTanMargin * view.TanFovY();
  const double z = 2.5;
  int case_index = 0;
  for (const double fx_side : {0.97, 1.03, -0.97, -1.03}) {
    for (const double fy_side : {0.97, 1.03, -1.03, 0.0}) {
      SCOPED_TRACE(case_index++);
      const Vec3<double> p(fx_side * lim_x * z, fy_side * lim_y * z, z);
      CheckProjectionGradient(view, WorldFromCamera(view, p),
                              RandomCov(rng, Vec3<double>(0.2, 0.1, 0.3)), rng);
    }
  }
}

TEST(ProjectEwa, BackwardWithNearlyDegenerateCovariance) {
  // A needle (one axis 1e4 x the others): the dilation keeps the 2D covariance invertible.
  // The conic now varies on covariance scales of ~dilation / (fx/z)^2 ~ 2e-4, so the FD step
  // shrinks to 1e-8 to keep the truncation error (h / 2e-4)^2 negligible.
  for (unsigned seed = 40; seed < 44; ++seed) {
    std::mt19937 rng(seed);
    const ViewParams<double> view = RandomView(rng);
    const Vec3<double> p(0.1, -0.2, 2.0);
    SCOPED_TRACE(seed);
    CheckProjectionGradient(view, WorldFromCamera(view, p),
                            RandomCov(rng, Vec3<double>(0.5, 1e-4, 1e-4)), rng, 1e-8);
  }
}

// The per-Gaussian preprocess the renderer runs: (mean4, log_scales, q_l, q_r) -> Rotation4D
// -> Covariance4D -> SliceAtTime -> ProjectEwa, with L = wm . mean2d + wc . conic + wp p(t).
struct ChainOutput {
  Splat2D<double> splat;
  double marginal;
};
ChainOutput RunChain(const Vec& x, double t, const ViewParams<double>& view) {
  const Vec4<double> mean4 = x.segment<4>(0), ls = x.segment<4>(4);
  const Mat4<double> R = Rotation4D<double>(x.segment<4>(8), x.segment<4>(12));
  const Slice<double> s = SliceAtTime(mean4, Covariance4D(R, ls), t);
  return {ProjectEwa(s.mean, s.cov, view), s.marginal};
}

TEST(Preprocess4D, ChainGradientMatchesFiniteDifferences) {
  for (unsigned seed = 50; seed < 58; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const ViewParams<double> view = RandomView(rng);
    const Vec3<double> p(0.3 * u(rng), 0.3 * u(rng), 3.0 + u(rng));
    Vec x(16);
    x << WorldFromCamera(view, p), 0.5 * (u(rng) + 1),  // mean4
        std::log(0.15) + 0.4 * u(rng), std::log(0.15) + 0.4 * u(rng), std::log(0.15) + 0.4 * u(rng),
        std::log(0.4) + 0.3 * u(rng),  // log_scales
        RandomQuaternion(rng), RandomQuaternion(rng);
    const double t = x(3) + 0.3 * u(rng);
    const Vec2<double> wm = Vec2<double>(n(rng), n(rng)) / view.fx;
    const Vec3<double> wc(n(rng), n(rng), n(rng));
    const double wp = n(rng);
    auto loss = [&](const Vec& v) {
      const ChainOutput out = RunChain(v, t, view);
      return wm.dot(out.splat.mean) + wc.dot(out.splat.conic) + wp * out.marginal;
    };
    ASSERT_TRUE(RunChain(x, t, view).splat.visible);

    // Backward in reverse order, as the renderer will call it.
    const Vec4<double> mean4 = x.segment<4>(0), ls = x.segment<4>(4), ql = x.segment<4>(8),
                       qr = x.segment<4>(12);
    const Mat4<double> R = Rotation4D(ql, qr);
    const Mat4<double> sigma = Covariance4D(R, ls);
    const Slice<double> s = SliceAtTime(mean4, sigma, t);
    Vec3<double> dmean3;
    Mat3<double> dcov3;
    ProjectEwaBackward(s.mean, s.cov, view, wm, wc, &dmean3, &dcov3);
    Vec4<double> dmean4, dls, dql, dqr;
    Mat4<double> dsigma, dR;
    SliceAtTimeBackward(mean4, sigma, t, dmean3, dcov3, wp, &dmean4, &dsigma);
    Covariance4DBackward(R, ls, dsigma, &dR, &dls);
    Rotation4DBackward(ql, qr, dR, &dql, &dqr);
    Vec analytic(16);
    analytic << dmean4, dls, dql, dqr;
    SCOPED_TRACE(seed);
    kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));

    // The float forward agrees with double (the training precision).
    const Mat4<float> Rf = Rotation4D<float>(ql.cast<float>(), qr.cast<float>());
    const Slice<float> sf = SliceAtTime<float>(
        mean4.cast<float>(), Covariance4D<float>(Rf, ls.cast<float>()), static_cast<float>(t));
    ViewParams<float> viewf{view.rotation.cast<float>(),
                            view.translation.cast<float>(),
                            static_cast<float>(view.fx),
                            static_cast<float>(view.fy),
                            static_cast<float>(view.cx),
                            static_cast<float>(view.cy),
                            view.width,
                            view.height};
    const Splat2D<float> splat_f = ProjectEwa(sf.mean, sf.cov, viewf);
    const Splat2D<double> splat_d = ProjectEwa(s.mean, s.cov, view);
    EXPECT_LT((splat_f.mean.cast<double>() - splat_d.mean).norm(), 1e-3);
    EXPECT_LT((splat_f.conic.cast<double>() - splat_d.conic).norm(), 1e-4 * splat_d.conic.norm());
    EXPECT_NEAR(sf.marginal, s.marginal, 1e-5);
  }
}

TEST(Preprocess4D, FloatBackwardMatchesDouble) {
  // The training precision: the whole backward chain in float agrees with double.
  std::mt19937 rng(60);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    const ViewParams<double> view = RandomView(rng);
    const Vec4<double> mean4(
        WorldFromCamera(view, Vec3<double>(0.3 * u(rng), 0.3 * u(rng), 3)).homogeneous());
    const Vec4<double> ls(std::log(0.2), std::log(0.1), std::log(0.15), std::log(0.4));
    const Vec4<double> ql = RandomQuaternion(rng), qr = RandomQuaternion(rng);
    const double t = mean4(3) + 0.2 * u(rng);
    const Vec2<double> wm(n(rng), n(rng));
    const Vec3<double> wc(n(rng), n(rng), n(rng));
    const double wp = n(rng);
    auto run = [&]<typename T>(T) {
      ViewParams<T> v{view.rotation.cast<T>(),
                      view.translation.cast<T>(),
                      T(view.fx),
                      T(view.fy),
                      T(view.cx),
                      T(view.cy),
                      view.width,
                      view.height};
      const Vec4<T> m4 = mean4.cast<T>(), s4 = ls.cast<T>(), l4 = ql.cast<T>(), r4 = qr.cast<T>();
      const Mat4<T> R = Rotation4D(l4, r4);
      const Mat4<T> sigma = Covariance4D(R, s4);
      const Slice<T> s = SliceAtTime(m4, sigma, T(t));
      Vec3<T> dmean3;
      Mat3<T> dcov3, dR3;
      ProjectEwaBackward<T>(s.mean, s.cov, v, wm.cast<T>(), wc.cast<T>(), &dmean3, &dcov3);
      Vec4<T> dmean4, dls, dql, dqr, dq3;
      Mat4<T> dsigma, dR;
      SliceAtTimeBackward<T>(m4, sigma, T(t), dmean3, dcov3, T(wp), &dmean4, &dsigma);
      Covariance4DBackward(R, s4, dsigma, &dR, &dls);
      Rotation4DBackward(l4, r4, dR, &dql, &dqr);
      // The 3D-mode pieces in the same precision.
      Vec3<T> dls3;
      Covariance3DBackward<T>(Rotation3D(l4), s4.template head<3>(), dcov3, &dR3, &dls3);
      Rotation3DBackward(l4, dR3, &dq3);
      Eigen::Matrix<double, 23, 1> g;
      g << dmean4.template cast<double>(), dls.template cast<double>(), dql.template cast<double>(),
          dqr.template cast<double>(), dq3.template cast<double>(), dls3.template cast<double>();
      return g;
    };
    const Eigen::Matrix<double, 23, 1> gd = run(0.0), gf = run(0.0f);
    ASSERT_TRUE(gf.allFinite());
    EXPECT_LT((gf - gd).cwiseAbs().maxCoeff(), 1e-4 * gd.cwiseAbs().maxCoeff())
        << gf.transpose() << "\n"
        << gd.transpose();
  }
}

}  // namespace
}  // namespace hdr4d::method
