#include "core/dataset/demo_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

TEST(DemoScene, RadianceSpansAHighDynamicRange) {
  testing::TempDir dir;
  DemoSceneOptions options;
  options.width = options.height = 48;
  options.num_timestamps = 3;
  options.num_cameras = 3;
  const Dataset dataset = MakeDemoScene(options, dir.path());
  std::vector<float> luminance;
  for (const Frame* f : dataset.AllFrames()) {
    const Image hdr = ReadImage(*f->hdr_path);
    for (std::size_t i = 0; i < hdr.num_pixels(); ++i) {
      const float* p = hdr.data() + i * 3;
      luminance.push_back(0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2]);
    }
  }
  std::sort(luminance.begin(), luminance.end());
  EXPECT_GT(luminance.back(), 4.0f);   // the bulb is in view somewhere...
  EXPECT_LT(luminance.back(), 8.0f);   // ...and within the 0.125 s exposure's range
  EXPECT_GT(luminance.front(), 0.0f);  // ambient fill: no pure black
  EXPECT_GT(luminance.back() / luminance.front(), 1e4f);
}

TEST(DemoScene, EmitterProjectsToTheBrightestPixel) {
  // Checks the whole camera chain: dataset pose (OpenGL axes) -> OpenCV -> pixel convention.
  testing::TempDir dir;
  DemoSceneOptions options;
  options.width = options.height = 64;
  options.num_timestamps = 2;
  options.num_cameras = 4;
  options.samples_per_axis = 1;
  const Dataset dataset = MakeDemoScene(options, dir.path());
  int checked = 0;
  for (const Frame* f : dataset.AllFrames()) {
    const auto uvd = f->camera.Project(DemoEmitterCenter(f->time));
    if (!uvd || (*uvd)[0] < 2 || (*uvd)[1] < 2 || (*uvd)[0] > 62 || (*uvd)[1] > 62) continue;
    // Centroid of the bulb's pixels (it is a disk of constant radiance, brighter than anything).
    const Image hdr = ReadImage(*f->hdr_path);
    double sx = 0, sy = 0, n = 0;
    for (int y = 0; y < hdr.height(); ++y)
      for (int x = 0; x < hdr.width(); ++x)
        if (hdr.at(x, y, 0) > 5.9f) sx += x + 0.5, sy += y + 0.5, n += 1;
    if (n == 0) continue;  // hidden behind the ball
    EXPECT_NEAR(sx / n, (*uvd)[0], 0.5) << f->file_path;
    EXPECT_NEAR(sy / n, (*uvd)[1], 0.5) << f->file_path;
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(DemoScene, LayoutMatchesTheRig) {
  testing::TempDir dir;
  DemoSceneOptions options;
  options.width = options.height = 16;
  options.num_timestamps = 4;
  options.num_cameras = 3;
  options.samples_per_axis = 1;
  const Dataset multi = MakeDemoScene(options, dir / "multi");
  EXPECT_EQ(multi.train.size(), 2u * 4 * 3);  // 2 train cameras x 4 times x 3 exposures
  EXPECT_EQ(multi.test.size(), 1u * 4 * 3);
  const Dataset loaded = LoadDataset(dir / "multi", {.image_check = ImageCheck::kNone});
  EXPECT_EQ(loaded.train.size(), multi.train.size());
  EXPECT_DOUBLE_EQ(loaded.test.back().time, 1.0);

  options.rig = DemoRig::kMonocular;
  options.num_timestamps = 8;
  const Dataset mono = MakeDemoScene(options, dir / "mono");
  EXPECT_EQ(mono.train.size() + mono.test.size(), 8u);
  EXPECT_EQ(mono.test.size(), 2u);  // frames 3 and 7
  // Exposures cycle over the frames.
  EXPECT_DOUBLE_EQ(mono.train[0].exposure, 0.125);
  EXPECT_DOUBLE_EQ(mono.train[1].exposure, 2.0);
  EXPECT_DOUBLE_EQ(mono.train[2].exposure, 32.0);
}

TEST(DemoScene, SceneChangesOverTime) {
  const Camera camera{
      PinholeIntrinsics::FromFovX(0.8, 32, 32),
      (Eigen::Matrix4d() << 1, 0, 0, 0, 0, 0, -1, -4, 0, 1, 0, 1, 0, 0, 0, 1).finished()};
  const Image a = RenderDemoView(camera, 0.0, 1), b = RenderDemoView(camera, 1.0, 1);
  double diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff += std::abs(a.values()[i] - b.values()[i]);
  EXPECT_GT(diff / a.size(), 0.01);
}

TEST(DemoScene, BadOptionsAreErrors) {
  DemoSceneOptions options;
  options.exposures = {2.0, 0.0};
  EXPECT_THROW(options.Validate(), Error);
  options = {};
  options.num_cameras = 1;
  EXPECT_THROW(options.Validate(), Error);
  options = {};
  options.width = 2;
  EXPECT_THROW(options.Validate(), Error);
}

}  // namespace
}  // namespace hdr4d
