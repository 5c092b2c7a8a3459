#include "calibration/board_calibration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/image/image_io.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

namespace fs = std::filesystem;

const BoardSpec kBoard{9, 6, 0.03};
constexpr double kF = 600, kCx = 320, kCy = 240;

// board_from_cam for a camera at `centre` (board frame, metres) looking at the board's middle.
Eigen::Matrix4d CameraAt(const Eigen::Vector3d& centre) {
  const Eigen::Vector3d target(4 * kBoard.square, 2.5 * kBoard.square, 0);
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 1>(0, 0) = x;
  m.block<3, 1>(0, 1) = y;
  m.block<3, 1>(0, 2) = z;
  m.block<3, 1>(0, 3) = centre;
  return m;
}

// A pinhole render of the board (2x2 supersampled), white around it.
void RenderBoard(const fs::path& path, const Eigen::Matrix4d& board_from_cam) {
  Image image(640, 480, 3, Encoding::kSrgb);
  const Eigen::Matrix3d r = board_from_cam.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = board_from_cam.topRightCorner<3, 1>();
  for (int v = 0; v < image.height(); ++v)
    for (int u = 0; u < image.width(); ++u) {
      double sum = 0;
      for (int s = 0; s < 4; ++s) {
        const Eigen::Vector3d d = r * Eigen::Vector3d((u + 0.25 + 0.5 * (s % 2) - kCx) / kF,
                                                      (v + 0.25 + 0.5 * (s / 2) - kCy) / kF, 1);
        const double k = -t.z() / d.z();
        const Eigen::Vector3d p = t + k * d;
        const int i = static_cast<int>(std::floor(p.x() / kBoard.square)) + 1;
        const int j = static_cast<int>(std::floor(p.y() / kBoard.square)) + 1;
        const bool on_board = k > 0 && i >= 0 && j >= 0 && i <= kBoard.cols && j <= kBoard.rows;
        sum += on_board && (i + j) % 2 == 0 ? 0.05 : 0.95;
      }
      for (int c = 0; c < 3; ++c) image.at(u, v, c) = static_cast<float>(sum / 4);
    }
  WriteImage(path, image);
}

TEST(BoardCalibration, RecoversFocalLengthAndMetricBaseline) {
  testing::TempDir dir;
  // Camera a: three views of the board; camera b: one, taken at the same moment as a's "shot".
  const Eigen::Matrix4d a_shot = CameraAt({0.05, 0.02, -0.45});
  RenderBoard(dir / "a" / "shot.png", a_shot);
  RenderBoard(dir / "a" / "left.png", CameraAt({-0.08, 0.1, -0.45}));
  RenderBoard(dir / "a" / "high.png", CameraAt({0.12, -0.08, -0.45}));
  const Eigen::Matrix4d b_shot = CameraAt({0.3, 0.1, -0.4});
  RenderBoard(dir / "b" / "shot.png", b_shot);
  WriteImage(dir / "b" / "blank.png", Image(640, 480, 3, Encoding::kSrgb, 0.7f));  // no board

  const BoardCalibration a = CalibrateFromBoard({dir / "a" / "shot.png", dir / "a" / "left.png", dir / "a" / "high.png"}, kBoard);
  const BoardCalibration b = CalibrateFromBoard({dir / "b" / "shot.png", dir / "b" / "blank.png"}, kBoard);
  ASSERT_EQ(a.views, 3);
  ASSERT_EQ(b.views, 1);
  EXPECT_NEAR(a.intrinsics.f, kF, 0.01 * kF);
  EXPECT_NEAR(a.intrinsics.cx, kCx, 3);
  EXPECT_NEAR(b.intrinsics.f, kF, 0.02 * kF);
  EXPECT_LT(a.rms, 0.5);
  const Eigen::Vector3d centre = a.board_from_cam.at("shot.png").topRightCorner<3, 1>();
  EXPECT_LT((centre - a_shot.topRightCorner<3, 1>()).norm(), 0.01);  // metres
  // A reconstruction whose baseline between a and b is 2 units: metres per unit = baseline / 2.
  const double baseline = (a_shot.topRightCorner<3, 1>() - b_shot.topRightCorner<3, 1>()).norm();
  EXPECT_NEAR(MetresPerUnit(a, b, 2.0), baseline / 2, 0.02 * baseline / 2);
  EXPECT_EQ(MetresPerUnit(a, BoardCalibration{}, 2.0), 0);
}

TEST(BoardCalibration, BadSpecsAreErrors) {
  EXPECT_EQ(ParseBoardSpec("9x6:0.025").cols, 9);
  EXPECT_NE(testing::ErrorOf([] { ParseBoardSpec("9x6"); }).find("--board 9x6: expected"), std::string::npos);
  EXPECT_NE(testing::ErrorOf([] { ParseBoardSpec("1x6:0.02"); }).find("expected"), std::string::npos);
  EXPECT_NE(testing::ErrorOf([] { ParseBoardSpec("9x6:-1"); }).find("expected"), std::string::npos);
}

}  // namespace
}  // namespace hdr4d
