#include "method/train/train_views.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/geometry/camera.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/image/image.h"
#include "method/run/gaussian_scene.h"
#include "tests/testing.h"

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

// A small made scene (4 cameras, every 4th held out, 2 times) of size x size images.
Dataset MakeSmallScene(const std::filesystem::path& root, int size) {
  GaussianSceneOptions s;
  s.size = size;
  s.num_gaussians = 12;
  s.num_cameras = 4;
  s.num_timestamps = 2;
  return MakeGaussianScene(s, root);
}

// The test split is checked when training starts and read again at each evaluation
// (CheckViews): the views hold no pixels, and the images they read are those LoadViews keeps.
TEST(CheckViews, HoldsNoPixelsAndReadsWhatLoadViewsKeeps) {
  hdr4d::testing::TempDir dir;
  const Dataset dataset = MakeSmallScene(dir / "scene", 24);
  const float background[3] = {0.2f, 0.3f, 0.4f};
  for (int resolution : {1, 2}) {
    const std::vector<TrainView> held =
        LoadViews(dataset, Split::kTest, background, false, resolution);
    const std::vector<TrainView> checked =
        CheckViews(dataset, Split::kTest, background, resolution);
    ASSERT_EQ(held.size(), checked.size());
    ASSERT_FALSE(held.empty());
    for (std::size_t i = 0; i < held.size(); ++i) {
      EXPECT_EQ(checked[i].rgb.capacity(), 0u) << "the pixels are held";
      EXPECT_EQ(checked[i].width(), held[i].width());
      EXPECT_EQ(checked[i].name, held[i].name);
      std::vector<float> a, b;
      held[i].ToFloat(&a);
      checked[i].ToFloat(&b);
      ASSERT_EQ(a.size(), static_cast<std::size_t>(24 / resolution) * (24 / resolution) * 3);
      EXPECT_EQ(a, b) << held[i].name << " at resolution " << resolution;
    }
  }
}

// A test image broken after the check is reported with its file when it is read again.
TEST(CheckViews, AnImageBrokenAfterTheCheckIsNamedWhenRead) {
  hdr4d::testing::TempDir dir;
  const Dataset dataset = MakeSmallScene(dir / "scene", 16);
  const float background[3] = {0, 0, 0};
  const std::vector<TrainView> views = CheckViews(dataset, Split::kTest, background);
  ASSERT_FALSE(views.empty());
  const std::filesystem::path file = dataset.FramesOf(Split::kTest).front().image_path;
  hdr4d::testing::WriteTextFile(file, "not a png");
  std::vector<float> out;
  const std::string read = hdr4d::testing::ErrorOf([&] { views.front().ToFloat(&out); });
  EXPECT_NE(read.find(file.filename().string()), std::string::npos) << "error: " << read;
  // And a broken image stops the check itself, naming the file.
  const std::string check =
      hdr4d::testing::ErrorOf([&] { CheckViews(dataset, Split::kTest, background); });
  EXPECT_NE(check.find(file.filename().string()), std::string::npos) << "error: " << check;
}

}  // namespace
}  // namespace hdr4d::method
