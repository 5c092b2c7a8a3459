#include "benchmark/scoring.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using testing::ErrorOf;
using testing::TempDir;

// A 16x16 scene: one train view and one camera's three test views at t = 0, 0.5, 1, each with
// LDR and HDR ground truth. The HDR is 1 everywhere except the cell (5, 2) of the 8x8 grid,
// which brightens 100x over time: the region to follow.
fs::path MakeScene(const fs::path& root) {
  const nlohmann::json pose = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 4}, {0, 0, 0, 1}};
  nlohmann::json train = {{"camera_angle_x", 0.7}, {"frames", nlohmann::json::array()}};
  nlohmann::json test = train;
  auto frame = [&](const std::string& name, double t) {
    Image hdr(16, 16, 3, Encoding::kLinear, 1.0f);
    for (int y = 4; y < 6; ++y)
      for (int x = 10; x < 12; ++x)
        for (int c = 0; c < 3; ++c) hdr.at(x, y, c) = static_cast<float>(std::pow(100.0, t));
    WriteImage(root / "hdr" / (name + ".exr"), hdr);
    Image ldr(16, 16, 3, Encoding::kSrgb, 0.5f);
    WriteImage(root / "images" / (name + ".png"), ldr);
    return nlohmann::json{{"file_path", "images/" + name + ".png"},
                          {"exr_file_path", "hdr/" + name + ".exr"},
                          {"transform_matrix", pose}, {"time", t}, {"exposures", 1.0}, {"camera_id", 0}};
  };
  train["frames"].push_back(frame("train", 0.25));
  for (double t : {0.0, 0.5, 1.0}) test["frames"].push_back(frame("t" + std::to_string(int(t * 10)), t));
  WriteJsonFile(root / "transforms_train.json", train);
  WriteJsonFile(root / "transforms_test.json", test);
  return root;
}

// Renders that equal the ground truth, named as `hdr4d render` names them.
void PerfectRenders(const Dataset& d, const fs::path& out) {
  fs::create_directories(out);
  for (const Frame& f : d.test) {
    fs::copy_file(f.image_path, out / LdrRenderName(f), fs::copy_options::overwrite_existing);
    fs::copy_file(*f.hdr_path, out / HdrRenderName(f), fs::copy_options::overwrite_existing);
  }
}

TEST(Scoring, ScoresEveryFrameAndFindsTheChangingRegion) {
  TempDir dir;
  const Dataset d = LoadDataset(MakeScene(dir / "scene"));
  PerfectRenders(d, dir / "r");
  const ScoredRenders s = ScoreRenders(d, dir / "r", {.strict = true});
  ASSERT_EQ(s.frames.size(), 6u);  // 3 LDR + 3 HDR
  for (const FrameResult& f : s.frames) {
    const bool hdr = f.frame.rfind("hdr/", 0) == 0;
    EXPECT_TRUE(std::isinf(f.metrics.at(hdr ? "mu_psnr" : "psnr"))) << f.frame;
    EXPECT_EQ(f.metrics.count(hdr ? "psnr" : "mu_psnr"), 0u) << f.frame;
  }
  EXPECT_DOUBLE_EQ(s.region[0], 5.0 / 8);
  EXPECT_DOUBLE_EQ(s.region[1], 2.0 / 8);
  EXPECT_DOUBLE_EQ(s.region[2], 1.0 / 8);
  // The region's luminance follows the scene (100^t) in prediction and ground truth.
  for (const FrameResult& f : s.frames) {
    if (f.frame.rfind("hdr/", 0) != 0) continue;
    EXPECT_NEAR(f.stats.at("region_luminance"), std::pow(100.0, f.time), 1e-3 * std::pow(100.0, f.time));
    EXPECT_DOUBLE_EQ(f.stats.at("region_luminance"), f.stats.at("region_luminance_gt"));
  }
}

TEST(Scoring, SubmissionMistakesAreClearErrors) {
  TempDir dir;
  const Dataset d = LoadDataset(MakeScene(dir / "scene"));
  const fs::path r = dir / "r";
  PerfectRenders(d, r);
  fs::remove(r / "t5.png");
  std::string e = ErrorOf([&] { ScoreRenders(d, r, {.strict = true}); });
  EXPECT_NE(e.find("1 of the 3 LDR renders"), std::string::npos) << e;
  EXPECT_NE(e.find("t5.png"), std::string::npos) << e;

  PerfectRenders(d, r);
  WriteImage(r / "t99.png", Image(16, 16, 3, Encoding::kSrgb));
  e = ErrorOf([&] { ScoreRenders(d, r, {.strict = true}); });
  EXPECT_NE(e.find("t99.png"), std::string::npos) << e;
  EXPECT_NO_THROW(ScoreRenders(d, r, {.strict = false}));  // harness renders: extra files ignored
  fs::remove(r / "t99.png");

  WriteImage(r / "t0.png", Image(8, 8, 3, Encoding::kSrgb));
  e = ErrorOf([&] { ScoreRenders(d, r, {.strict = true}); });
  EXPECT_NE(e.find("differ in size"), std::string::npos) << e;
  EXPECT_NE(e.find("t0.png"), std::string::npos) << e;

  PerfectRenders(d, r);
  Image nan(16, 16, 3, Encoding::kLinear, 1.0f);
  nan.at(3, 3, 1) = NAN;
  WriteImage(r / "t10.exr", nan, {.format = PixelFormat::kFloat});
  e = ErrorOf([&] { ScoreRenders(d, r, {.strict = true}); });
  EXPECT_NE(e.find("t10.exr"), std::string::npos) << e;
  EXPECT_NE(e.find("non-finite"), std::string::npos) << e;

  TempDir empty;
  e = ErrorOf([&] { ScoreRenders(d, empty.path(), {.strict = true}); });
  EXPECT_NE(e.find("no render is named like"), std::string::npos) << e;
}

TEST(Scoring, AKindAMethodDoesNotOutputIsLeftOut) {
  TempDir dir;
  const Dataset d = LoadDataset(MakeScene(dir / "scene"));
  PerfectRenders(d, dir / "r");
  for (const char* f : {"t0.exr", "t5.exr", "t10.exr"}) fs::remove(dir / "r" / f);
  const ScoredRenders s = ScoreRenders(d, dir / "r", {});
  EXPECT_EQ(s.frames.size(), 3u);
}

}  // namespace
}  // namespace hdr4d::bench
