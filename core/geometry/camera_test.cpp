#include "core/geometry/camera.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "core/util/error.h"

namespace hdr4d {
namespace {

// Lego (D-NeRF) at 100x100: camera_angle_x from its transforms_train.json.
constexpr double kLegoAngle = 0.6911112070083618;

Camera CameraAtZ5() {
  Camera camera;
  camera.intrinsics = PinholeIntrinsics::FromFovX(kLegoAngle, 100, 80);
  camera.world_from_cam_gl = LookAtWorldFromCamGl({0, 0, 5}, {0, 0, 0});
  return camera;
}

Eigen::Matrix4d RandomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  const Eigen::Quaterniond q =
      Eigen::Quaterniond(dist(rng), dist(rng), dist(rng), dist(rng)).normalized();
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  pose.topLeftCorner<3, 3>() = q.toRotationMatrix();
  pose.topRightCorner<3, 1>() = Eigen::Vector3d(dist(rng), dist(rng), dist(rng)) * 4.0;
  return pose;
}

TEST(PinholeIntrinsics, FromFovXGoldenLego) {
  const PinholeIntrinsics k = PinholeIntrinsics::FromFovX(kLegoAngle, 100, 100);
  // fl_x written in the lego transforms: 138.88887889922103.
  EXPECT_NEAR(k.fx, 138.88887889922103, 1e-9);
  EXPECT_EQ(k.fx, k.fy);
  EXPECT_EQ(k.cx, 50.0);
  EXPECT_EQ(k.cy, 50.0);
  EXPECT_EQ(k.width, 100);
  EXPECT_EQ(k.height, 100);
  EXPECT_NEAR(k.FovX(), kLegoAngle, 1e-12);
  EXPECT_NEAR(k.FovY(), kLegoAngle, 1e-12);  // square image, square pixels
}

TEST(PinholeIntrinsics, FromFovXNonSquareAnd90Degrees) {
  const PinholeIntrinsics k = PinholeIntrinsics::FromFovX(M_PI / 2, 800, 600);
  EXPECT_NEAR(k.fx, 400.0, 1e-9);  // tan(45 deg) = 1
  EXPECT_NEAR(k.fy, 400.0, 1e-9);
  EXPECT_EQ(k.cx, 400.0);
  EXPECT_EQ(k.cy, 300.0);
  EXPECT_NEAR(k.FovY(), 2 * std::atan(300.0 / 400.0), 1e-12);
}

TEST(PinholeIntrinsics, FromFovXRejectsBadInput) {
  EXPECT_THROW(PinholeIntrinsics::FromFovX(0.0, 10, 10), Error);
  EXPECT_THROW(PinholeIntrinsics::FromFovX(-0.5, 10, 10), Error);
  EXPECT_THROW(PinholeIntrinsics::FromFovX(M_PI, 10, 10), Error);
  EXPECT_THROW(PinholeIntrinsics::FromFovX(std::nan(""), 10, 10), Error);
  EXPECT_THROW(PinholeIntrinsics::FromFovX(1.0, 0, 10), Error);
  EXPECT_THROW(PinholeIntrinsics::FromFovX(1.0, 10, -1), Error);
}

TEST(PinholeIntrinsics, ValidateNamesTheProblem) {
  PinholeIntrinsics k = PinholeIntrinsics::FromFovX(1.0, 10, 10);
  EXPECT_NO_THROW(k.Validate());
  EXPECT_TRUE(k.Problem().empty());
  k.fy = 0;
  EXPECT_NE(k.Problem().find("focal"), std::string::npos);
  EXPECT_THROW(k.Validate(), Error);
  k.fy = k.fx;
  k.cx = std::numeric_limits<double>::infinity();
  EXPECT_NE(k.Problem().find("principal point"), std::string::npos);
  k.cx = 5;
  k.height = 0;
  EXPECT_NE(k.Problem().find("size"), std::string::npos);
}

TEST(Camera, LookAtAlongMinusZIsIdentityRotation) {
  const Camera camera = CameraAtZ5();
  EXPECT_TRUE((camera.world_from_cam_gl.topLeftCorner<3, 3>().isIdentity(1e-15)));
  EXPECT_TRUE(camera.Center().isApprox(Eigen::Vector3d(0, 0, 5)));
  EXPECT_TRUE(camera.ViewDirection().isApprox(Eigen::Vector3d(0, 0, -1)));
}

TEST(Camera, KnownPointsProjectWhereExpected) {
  const Camera camera = CameraAtZ5();
  const PinholeIntrinsics& k = camera.intrinsics;
  const auto origin = camera.Project({0, 0, 0});
  ASSERT_TRUE(origin.has_value());
  EXPECT_NEAR((*origin)(0), k.cx, 1e-12);
  EXPECT_NEAR((*origin)(1), k.cy, 1e-12);
  EXPECT_NEAR((*origin)(2), 5.0, 1e-12);

  // +X world is the camera's right: u grows. Exact value fx * 1 / 5 + cx.
  const auto right = camera.Project({1, 0, 0});
  ASSERT_TRUE(right.has_value());
  EXPECT_NEAR((*right)(0), k.fx / 5.0 + k.cx, 1e-9);
  EXPECT_GT((*right)(0), k.cx);
  EXPECT_NEAR((*right)(1), k.cy, 1e-9);

  // +Y world is up in the picture: image v (growing downwards) shrinks.
  const auto above = camera.Project({0, 1, 0});
  ASSERT_TRUE(above.has_value());
  EXPECT_LT((*above)(1), k.cy);
  EXPECT_NEAR((*above)(1), k.cy - k.fy / 5.0, 1e-9);
  EXPECT_NEAR((*above)(0), k.cx, 1e-9);
}

TEST(Camera, KnownPointsInBothConventions) {
  const Camera camera = CameraAtZ5();
  // OpenCV camera frame: the point (1, 1, 0) is right (+x) and up (-y), 5 in front (+z).
  const Eigen::Vector4d p_cv = camera.CamFromWorldCv() * Eigen::Vector4d(1, 1, 0, 1);
  EXPECT_TRUE(p_cv.head<3>().isApprox(Eigen::Vector3d(1, -1, 5), 1e-12));
  // OpenGL camera frame: right (+x), up (+y), in front is -z.
  const Eigen::Vector4d p_gl = camera.CamFromWorldGl() * Eigen::Vector4d(1, 1, 0, 1);
  EXPECT_TRUE(p_gl.head<3>().isApprox(Eigen::Vector3d(1, 1, -5), 1e-12));
  EXPECT_TRUE((CvFromGl() * p_gl).isApprox(p_cv, 1e-12));
}

TEST(Camera, RotatedCameraProjectsItsTarget) {
  Camera camera;
  camera.intrinsics = PinholeIntrinsics::FromFovX(0.9, 64, 48);
  const Eigen::Vector3d target(0.3, -0.2, 0.1);
  camera.world_from_cam_gl = LookAtWorldFromCamGl({2, 3, -4}, target, Eigen::Vector3d::UnitZ());
  const auto uvd = camera.Project(target);
  ASSERT_TRUE(uvd.has_value());
  EXPECT_NEAR((*uvd)(0), 32.0, 1e-9);
  EXPECT_NEAR((*uvd)(1), 24.0, 1e-9);
  EXPECT_NEAR((*uvd)(2), (Eigen::Vector3d(2, 3, -4) - target).norm(), 1e-9);
  // A point higher along world +Z (the chosen up) appears above the target.
  const auto higher = camera.Project(target + Eigen::Vector3d(0, 0, 0.5));
  ASSERT_TRUE(higher.has_value());
  EXPECT_LT((*higher)(1), 24.0);
}

TEST(Camera, BehindAndOnCameraPlaneRejected) {
  const Camera camera = CameraAtZ5();
  EXPECT_FALSE(camera.Project({0, 0, 6}).has_value());     // behind
  EXPECT_FALSE(camera.Project({1, 2, 5}).has_value());     // on the camera plane (depth 0)
  EXPECT_FALSE(camera.Project({0, 0, 100}).has_value());   // far behind
  EXPECT_TRUE(camera.Project({0, 0, 4.999}).has_value());  // just in front
}

TEST(Camera, ProjectUnprojectRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pix(-20.0, 120.0), depth(0.1, 30.0);
  for (int trial = 0; trial < 50; ++trial) {
    Camera camera;
    camera.intrinsics = {.fx = 90.0 + trial,
                         .fy = 110 - trial * 0.5,
                         .cx = 47.3,
                         .cy = 52.1,
                         .width = 100,
                         .height = 100};
    camera.world_from_cam_gl = RandomPose(rng);
    const double u = pix(rng), v = pix(rng), d = depth(rng);
    const Eigen::Vector3d world = camera.Unproject(u, v, d);
    const auto back = camera.Project(world);
    ASSERT_TRUE(back.has_value());
    EXPECT_NEAR((*back)(0), u, 1e-8);
    EXPECT_NEAR((*back)(1), v, 1e-8);
    EXPECT_NEAR((*back)(2), d, 1e-9);
    // Depth is the distance along the viewing direction.
    EXPECT_NEAR((world - camera.Center()).dot(camera.ViewDirection()), d, 1e-9);
  }
}

TEST(Camera, GlCvConversionsAreConsistent) {
  std::mt19937 rng(3);
  const Eigen::Matrix4d flip = GlFromCv();
  EXPECT_TRUE(flip.isApprox(Eigen::Vector4d(1, -1, -1, 1).asDiagonal().toDenseMatrix()));
  EXPECT_TRUE((GlFromCv() * CvFromGl()).isIdentity());
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix4d world_from_gl = RandomPose(rng);
    const Eigen::Matrix4d world_from_cv = WorldFromCamCvFromGl(world_from_gl);
    EXPECT_TRUE(WorldFromCamGlFromCv(world_from_cv).isApprox(world_from_gl, 1e-14));
    // The centre is the same, the Y and Z axes flip.
    EXPECT_TRUE(world_from_cv.col(3).isApprox(world_from_gl.col(3)));
    EXPECT_TRUE(world_from_cv.col(0).isApprox(world_from_gl.col(0)));
    EXPECT_TRUE(world_from_cv.col(1).isApprox(-world_from_gl.col(1)));
    EXPECT_TRUE(world_from_cv.col(2).isApprox(-world_from_gl.col(2)));
    const Camera camera{PinholeIntrinsics::FromFovX(1.0, 10, 10), world_from_gl};
    EXPECT_TRUE(camera.WorldFromCamCv().isApprox(world_from_cv));
    EXPECT_TRUE((camera.CamFromWorldCv() * world_from_cv).isIdentity(1e-12));
    EXPECT_TRUE(camera.CamFromWorldCv().isApprox(world_from_cv.inverse(), 1e-12));
    const Camera from_cv = Camera::FromWorldFromCamCv(camera.intrinsics, world_from_cv);
    EXPECT_TRUE(from_cv.world_from_cam_gl.isApprox(world_from_gl, 1e-14));
  }
}

TEST(Camera, RigidInverseMatchesGeneralInverse) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Matrix4d pose = RandomPose(rng);
    EXPECT_TRUE(RigidInverse(pose).isApprox(pose.inverse(), 1e-12));
    EXPECT_TRUE((RigidInverse(pose) * pose).isIdentity(1e-12));
  }
}

TEST(PoseProblem, AcceptsRotationsWithFloat32Rounding) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    Eigen::Matrix4d pose = RandomPose(rng);
    EXPECT_EQ(PoseProblem(pose), "");
    pose = pose.cast<float>().cast<double>();  // as stored in a float32 dataset
    EXPECT_EQ(PoseProblem(pose), "");
  }
  Eigen::Matrix4d nearly = Eigen::Matrix4d::Identity();
  nearly(0, 1) = 4e-4;  // within the 1e-3 tolerance
  EXPECT_EQ(PoseProblem(nearly), "");
}

TEST(PoseProblem, RejectsBrokenMatrices) {
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  pose(1, 2) = std::nan("");
  EXPECT_NE(PoseProblem(pose).find("non-finite"), std::string::npos);
  pose = Eigen::Matrix4d::Identity();
  pose(0, 3) = std::numeric_limits<double>::infinity();
  EXPECT_NE(PoseProblem(pose).find("non-finite"), std::string::npos);

  pose = Eigen::Matrix4d::Identity();
  pose(3, 0) = 0.5;
  EXPECT_NE(PoseProblem(pose).find("bottom row"), std::string::npos);
  pose = Eigen::Matrix4d::Identity();
  pose(3, 3) = 2;
  EXPECT_NE(PoseProblem(pose).find("bottom row"), std::string::npos);

  pose = Eigen::Matrix4d::Identity();
  pose.row(2).head<3>() = pose.row(1).head<3>();  // two equal rows
  EXPECT_NE(PoseProblem(pose).find("singular"), std::string::npos);
  Eigen::Matrix4d zero_rotation = Eigen::Matrix4d::Zero();
  zero_rotation(3, 3) = 1;
  EXPECT_NE(PoseProblem(zero_rotation).find("singular"), std::string::npos);

  pose = Eigen::Matrix4d::Identity();
  pose(2, 2) = -1;
  EXPECT_NE(PoseProblem(pose).find("reflection"), std::string::npos);

  pose = Eigen::Matrix4d::Identity();
  pose.topLeftCorner<3, 3>() *= 2.0;  // uniform scale
  EXPECT_NE(PoseProblem(pose).find("not a rotation"), std::string::npos);
  pose = Eigen::Matrix4d::Identity();
  pose(0, 1) = 0.2;  // shear
  EXPECT_NE(PoseProblem(pose).find("not a rotation"), std::string::npos);
  pose = Eigen::Matrix4d::Identity();
  pose(0, 1) = 2e-3;  // just beyond the tolerance
  EXPECT_NE(PoseProblem(pose).find("not a rotation"), std::string::npos);
}

TEST(Camera, ValidateThrowsForBadPoseOrIntrinsics) {
  Camera camera = CameraAtZ5();
  EXPECT_NO_THROW(camera.Validate());
  camera.world_from_cam_gl(0, 0) = 3;
  try {
    camera.Validate();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("transform_matrix"), std::string::npos) << e.what();
  }
  camera = CameraAtZ5();
  camera.intrinsics.fx = -1;
  EXPECT_THROW(camera.Validate(), Error);
}

}  // namespace
}  // namespace hdr4d
