// Stop 94's sweep of valid but extreme scenes (one fixed camera, tiny point clouds, grey + alpha
// images): each test names the defect of the sweep it covers (B-D1.., the second sweep's list)
// and failed before its fix.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/geometry/ply.h"
#include "core/image/image_io.h"
#include "tests/hostile_scene_fixture.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadTextFile;
using testing::RunHdr4d;

using ExtremeScenes = HostileScene;

json ReadJson(const fs::path& file) { return json::parse(ReadTextFile(file)); }

// B-D8, B-D6: one fixed camera (the demo's first camera alone trains) had a scene extent of 1e-3,
// and densification pruned every Gaussian as world-large after the first opacity reset: exit 0
// with 0 Gaussians. `render --video` of such a run aborted on an orbit of radius 0.
TEST_F(ExtremeScenes, BD08OneFixedCameraKeepsItsGaussiansAndRendersAVideo) {
  const fs::path train_json = fs::path(S()) / "transforms_train.json";
  json transforms = ReadJson(train_json);
  json kept = json::array();
  for (const json& f : transforms["frames"])
    if (f["camera_id"] == 0) kept.push_back(f);
  transforms["frames"] = kept;
  testing::WriteTextFile(train_json, transforms.dump(2));
  const std::string args = "train --data " + S() + " --out " + R() +
                           " --iterations 400 --opacity-reset-interval 100 --threads 1";
  const auto r = RunHdr4d(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(ReadJson(fs::path(R()) / "config.json")["scene_extent"].get<double>(), 0.5);
  EXPECT_GT(ReadJson(fs::path(R()) / "results.json")["gaussians"].get<int>(), 100);
  const auto video = RunHdr4d("render --run " + R() + " --video 3 --threads 1");
  EXPECT_EQ(video.exit_code, 0) << video.err;
  EXPECT_TRUE(fs::exists(fs::path(R()) / "video" / "frame_0002.png"));
}

// B-D1: a point3d.ply of fewer than 4 points was replaced by random points without a word.
TEST_F(ExtremeScenes, BD01ACloudTooSmallToStartFromIsNamed) {
  PointCloud tiny;
  tiny.positions = {{0, 0, 0}, {0.1f, 0, 0}};
  WritePly(fs::path(S()) / "point3d.ply", tiny);
  const auto r = RunHdr4d("train --data " + S() + " --out " + R() + " --iterations 5 --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("point3d.ply has 2 points, fewer than the 4"), std::string::npos) << r.err;
}

// B-D5: grey + alpha PNGs were refused ("has 2 channels") while RGBA ones were composited over the
// background; grey + alpha is composited the same way.
TEST_F(ExtremeScenes, BD05GreyAndAlphaImagesTrainAsRgbaDo) {
  for (const auto& e : fs::directory_iterator(fs::path(S()) / "images")) {
    const Image rgb = ReadImage(e.path());
    Image grey_alpha(rgb.width(), rgb.height(), 2, Encoding::kSrgb);
    for (std::size_t p = 0; p < rgb.num_pixels(); ++p) {
      grey_alpha.values()[p * 2] = rgb.values()[p * 3 + 1];
      grey_alpha.values()[p * 2 + 1] = p % 2 ? 1.0f : 0.5f;
    }
    WriteImage(e.path(), grey_alpha);
  }
  const auto check = RunHdr4d("dataset check " + S());
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  const auto r = RunHdr4d("train --data " + S() + " --out " + R() + " --iterations 20 --threads 1");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // The run's renders are RGB; eval reads the grey truth as RGB (B-D4).
  ASSERT_EQ(RunHdr4d("render --run " + R() + " --no-hdr --threads 1").exit_code, 0);
  const auto eval = RunHdr4d("eval " + R() + "/renders/test " + S() + "/images");
  EXPECT_EQ(eval.exit_code, 0) << eval.err;
}

}  // namespace
}  // namespace hdr4d
