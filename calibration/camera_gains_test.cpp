// The unlike cameras' gains on a synthetic rig: two cameras at different distances from a plane
// textured with a bright blob at every sparse point (as SIFT's features sit on blobs), the farther
// camera 25% more sensitive. A 3x3 window in each camera averages a larger patch of the blob in
// the farther camera and biases the gain; the same patch of surface in both does not.
#include "calibration/camera_gains.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/geometry/camera.h"

namespace hdr4d {
namespace {

constexpr int kSize = 400;
constexpr double kFocal = 400, kSigma = 0.008, kTrueGain = 1.25;

double Radiance(double x, double y, const std::vector<Eigen::Vector3f>& blobs) {
  double r = 0.2;
  for (const Eigen::Vector3f& b : blobs) {
    const double d2 = (x - b.x()) * (x - b.x()) + (y - b.y()) * (y - b.y());
    if (d2 < 36 * kSigma * kSigma) r += 2 * std::exp(-d2 / (2 * kSigma * kSigma));
  }
  return r;
}

// A camera at (cx, 0, -distance) looking along +z at the plane z = 0 (OpenCV axes: no rotation).
RigCamera PlaneCamera(const std::string& name, double x, double distance) {
  RigCamera camera;
  camera.name = name;
  camera.width = camera.height = kSize;
  camera.intrinsics = {kFocal, kSize / 2.0, kSize / 2.0};
  Eigen::Matrix4d world_from_cam_cv = Eigen::Matrix4d::Identity();
  world_from_cam_cv.topRightCorner<3, 1>() = Eigen::Vector3d(x, 0, -distance);
  camera.world_from_cam_gl = WorldFromCamGlFromCv(world_from_cam_cv);
  return camera;
}

// What the camera sees of the plane, each pixel sampled at its centre, times `gain`.
Image Render(const RigCamera& camera, const std::vector<Eigen::Vector3f>& blobs, double gain) {
  const Eigen::Vector3d centre = WorldFromCamCvFromGl(camera.world_from_cam_gl).topRightCorner<3, 1>();
  Image image(kSize, kSize, 3);
  for (int v = 0; v < kSize; ++v)
    for (int u = 0; u < kSize; ++u) {
      const double s = -centre.z();  // the ray (u - cx, v - cy, f) / f meets z = 0 there
      const double x = centre.x() + s * (u + 0.5 - camera.intrinsics.cx) / kFocal;
      const double y = centre.y() + s * (v + 0.5 - camera.intrinsics.cy) / kFocal;
      const float value = static_cast<float>(gain * Radiance(x, y, blobs));
      for (int c = 0; c < 3; ++c) image.at(u, v, c) = value;
    }
  return image;
}

TEST(CameraGains, TheSamePatchOfSurfaceInEveryCameraRemovesTheDistanceBias) {
  Rig rig;
  rig.cameras = {PlaneCamera("near", 0, 1.0), PlaneCamera("far", 0.05, 2.5)};
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j) {
      rig.points.positions.emplace_back(0.08f * i, 0.08f * j, 0.0f);
      rig.visibility.push_back({0, 1});
    }
  const std::vector<Image> hdr = {Render(rig.cameras[0], rig.points.positions, 1.0),
                                  Render(rig.cameras[1], rig.points.positions, kTrueGain)};
  const CameraGains same_patch = EstimateCameraGains(rig, hdr, kGainFootprintPixels);
  const CameraGains windows = EstimateCameraGains(rig, hdr, 0);
  EXPECT_EQ(same_patch.points_used, 121);
  EXPECT_EQ(same_patch.footprint_pixels, kGainFootprintPixels);
  for (int c = 0; c < 3; ++c) {
    const double ratio = same_patch.gain[1][c] / same_patch.gain[0][c];
    EXPECT_NEAR(ratio, kTrueGain, 0.02 * kTrueGain) << c;
    // The 3x3 windows: the far camera's window covers 2.5x more of each blob.
    EXPECT_LT(windows.gain[1][c] / windows.gain[0][c], 0.9 * kTrueGain) << c;
  }
  EXPECT_LT(same_patch.held_out_bias, windows.held_out_bias + 1e-12);
}

}  // namespace
}  // namespace hdr4d
