#include "method/train/train_views.h"

#include <gtest/gtest.h>

#include "core/camera.h"
#include "core/image.h"

namespace hdr4d::method {
namespace {

// --resolution R: every output pixel is the mean of its R x R block, per channel.
TEST(DownsampleBox, EachPixelIsTheMeanOfItsBlock) {
  Image image(6, 4, 3, Encoding::kSrgb);
  for (std::size_t i = 0; i < image.size(); ++i) image.values()[i] = float((i * 37) % 101) / 100;
  const Image half = DownsampleBox(image, 2);
  ASSERT_EQ(half.ShapeString(), "3x2x3");
  EXPECT_EQ(half.encoding(), Encoding::kSrgb);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c) {
        const double mean = (double(image.at(2 * x, 2 * y, c)) + image.at(2 * x + 1, 2 * y, c) +
                             image.at(2 * x, 2 * y + 1, c) + image.at(2 * x + 1, 2 * y + 1, c)) /
                            4;
        EXPECT_NEAR(half.at(x, y, c), mean, 1e-7);
      }
  EXPECT_EQ(DownsampleBox(image, 1).values(), image.values());
  const Image one = DownsampleBox(DownsampleBox(Image(4, 4, 1, Encoding::kLinear, 3.5f), 2), 2);
  EXPECT_EQ(one.ShapeString(), "1x1x1");
  EXPECT_EQ(one.at(0, 0, 0), 3.5f);
}

// A point lands at the same place relative to the image (pixel u at full size is u / R after
// the reduction), off-centre principal point and unequal focal lengths included.
TEST(DownscaledIntrinsics, ProjectsToTheSameRelativePosition) {
  Camera camera;
  camera.intrinsics = {.fx = 700, .fy = 690, .cx = 410.5, .cy = 385.25, .width = 800, .height = 792};
  camera.world_from_cam_gl = LookAtWorldFromCamGl({0.3, -0.2, 5}, {0, 0, 0});
  Camera small = camera;
  for (int factor : {1, 2, 4, 8}) {
    small.intrinsics = DownscaledIntrinsics(camera.intrinsics, factor);
    EXPECT_EQ(small.intrinsics.width, 800 / factor);
    EXPECT_EQ(small.intrinsics.height, 792 / factor);
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.4, -0.7, 0.2), Eigen::Vector3d(-1, 1, -1)}) {
      const auto full = camera.Project(p), reduced = small.Project(p);
      ASSERT_TRUE(full && reduced);
      EXPECT_NEAR((*reduced)(0) / small.intrinsics.width, (*full)(0) / 800, 1e-12);
      EXPECT_NEAR((*reduced)(1) / small.intrinsics.height, (*full)(1) / 792, 1e-12);
    }
  }
}

TEST(ResolutionProblem, NamesTheSizeAndTheFactor) {
  EXPECT_EQ(ResolutionProblem(800, 800, 4), "");
  EXPECT_NE(ResolutionProblem(800, 600, 0).find(">= 1"), std::string::npos);
  const std::string p = ResolutionProblem(64, 48, 5);
  EXPECT_NE(p.find("64x48"), std::string::npos) << p;
  EXPECT_NE(p.find("--resolution 5"), std::string::npos) << p;
}

}  // namespace
}  // namespace hdr4d::method
