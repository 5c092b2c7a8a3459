#include "core/radiometry/exposure_stack.h"

#include <gtest/gtest.h>

#include <iterator>

#include "core/dataset/dataset.h"
#include "core/dataset/demo_scene.h"
#include "core/dataset/val_split.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/metrics/metrics.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;

Dataset SmallScene(const fs::path& root) {
  DemoSceneOptions options;
  options.width = options.height = 24;
  options.num_timestamps = 2;
  options.num_cameras = 2;
  options.samples_per_axis = 1;
  return MakeDemoScene(options, root);
}

TEST(ExposureStack, SynthesisWritesEveryFrameBrighterWithExposure) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  const int n = SynthesizeDatasetLdr(dir.path(), {.crf = "gamma:2.2"});
  EXPECT_EQ(n, static_cast<int>(dataset.train.size() + dataset.test.size()));
  EXPECT_TRUE(fs::exists(dir / "synthesis.json"));
  // Same view and time at three exposures: mean brightness grows with exposure.
  double previous = -1;
  for (const Frame& f : dataset.train) {
    if (f.camera_id != 0 || f.time != 0.0) continue;
    const Image ldr = ReadImage(f.image_path);
    EXPECT_EQ(ldr.encoding(), Encoding::kSrgb);
    double mean = 0;
    for (float v : ldr.values()) mean += v;
    mean /= ldr.size();
    EXPECT_GT(mean, previous) << f.file_path;
    previous = mean;
  }
  // The whole dataset now validates with images decoded.
  EXPECT_TRUE(CheckDataset(dir.path(), {.image_check = ImageCheck::kFull}).problems.empty());
}

TEST(ExposureStack, GainDriftBrightensLateFramesAndDarkensEarlyOnes) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  auto mean_of = [](const fs::path& path) {
    const Image ldr = ReadImage(path);
    double mean = 0;
    for (float v : ldr.values()) mean += v;
    return mean / ldr.size();
  };
  SynthesizeDatasetLdr(dir.path(), {.crf = "gamma:2.2"});
  std::vector<double> fixed;
  for (const Frame& f : dataset.train) fixed.push_back(mean_of(f.image_path));
  SynthesizeDatasetLdr(dir.path(), {.crf = "gamma:2.2", .gain_drift = 2.0});
  for (std::size_t i = 0; i < dataset.train.size(); ++i) {
    const Frame& f = dataset.train[i];
    const double drifted = mean_of(f.image_path);
    if (f.time > 0.5) {
      EXPECT_GT(drifted, fixed[i]) << f.file_path;  // gain e^(+1)
    }
    if (f.time < 0.5) {
      EXPECT_LT(drifted, fixed[i]) << f.file_path;  // gain e^(-1)
    }
  }
  EXPECT_EQ(ReadJsonFile(dir / "synthesis.json")["gain_drift"], 2.0);
  EXPECT_THROW(SynthesizeDatasetLdr(dir.path(), {.gain_drift = 1e9}), Error);
}

TEST(ExposureStack, SameSeedSameBytes) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  DatasetSynthesisOptions options{.crf = "filmic",
                                  .noise = {.full_well = 1000, .read_sigma = 0.01, .seed = 7}};
  SynthesizeDatasetLdr(dir.path(), options);
  const std::string first = testing::ReadTextFile(dataset.train[0].image_path);
  SynthesizeDatasetLdr(dir.path(), options);
  EXPECT_EQ(first, testing::ReadTextFile(dataset.train[0].image_path));
  options.noise.seed = 8;
  SynthesizeDatasetLdr(dir.path(), options);
  EXPECT_NE(first, testing::ReadTextFile(dataset.train[0].image_path));
}

TEST(ExposureStack, MergeRecoversTheHdrBetterThanOneExposure) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  SynthesizeDatasetLdr(dir.path(), {.crf = "filmic"});
  EXPECT_EQ(MergeDatasetExposures(dir.path(), dir / "merged", {.split = "test"}), 2);
  for (const Frame& f : dataset.test) {
    if (f.exposure_index != 1) continue;
    const Image gt = ReadImage(*f.hdr_path);
    const Image merged = ReadImage(dir / "merged" / f.hdr_path->filename());
    const Image single = LinearizeLdr(ReadImage(f.image_path), *ParseCrf("filmic"), f.exposure);
    const double merged_pu = Pu21Psnr(merged, gt), single_pu = Pu21Psnr(single, gt);
    EXPECT_GT(merged_pu, 35.0) << f.file_path;
    EXPECT_GT(merged_pu, single_pu + 3.0) << f.file_path;
  }
}

// A dataset may mix grey LDR frames with RGB ones (training reads grey as RGB); the merge did
// not, and refused the bracket without naming a file.
TEST(ExposureStack, MergeReadsAGreyFrameAsRgb) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  SynthesizeDatasetLdr(dir.path(), {.crf = "filmic"});
  const Frame& grey_frame = dataset.test[0];
  const Image rgb = ReadImage(grey_frame.image_path);
  Image grey(rgb.width(), rgb.height(), 1, Encoding::kSrgb);
  for (std::size_t p = 0; p < grey.num_pixels(); ++p) grey.values()[p] = rgb.values()[p * 3 + 1];
  WriteImage(grey_frame.image_path, grey);
  EXPECT_EQ(MergeDatasetExposures(dir.path(), dir / "merged", {.split = "test"}), 2);
  const Image merged = ReadImage(dir / "merged" / grey_frame.hdr_path->filename());
  EXPECT_EQ(merged.channels(), 3);
}

TEST(ExposureStack, ErrorsNameTheProblem) {
  testing::TempDir dir;
  SmallScene(dir.path());
  // No synthesis.json yet and no --crf: the response is unknown.
  try {
    MergeDatasetExposures(dir.path(), dir / "m", {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("synthesis.json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SynthesizeDatasetLdr(dir.path(), {.crf = "gamma:-2"}), Error);
  EXPECT_THROW(MergeDatasetExposures(dir.path(), dir / "m", {.crf = "srgb", .split = "everything"}),
               Error);
  // A frame without HDR ground truth cannot be synthesised.
  nlohmann::json j = ReadJsonFile(dir / "transforms_train.json");
  j["frames"][0].erase("exr_file_path");
  WriteJsonFile(dir / "transforms_train.json", j);
  try {
    SynthesizeDatasetLdr(dir.path(), {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("exr_file_path"), std::string::npos) << e.what();
  }
}

// The sweep of session 94: synth-ldr --data on a `dataset split-val` copy, whose images/ links to
// the original's, rewrote the original's LDR images (with another response than its manifest's).
TEST(ExposureStack, SynthesisRefusesToWriteThroughALinkIntoAnotherScene) {
  testing::TempDir dir;
  SmallScene(dir / "S");
  SynthesizeDatasetLdr(dir / "S", {.crf = "filmic"});
  SplitOffVal(dir / "S", dir / "V", {.every_time = 2});
  const Dataset original = LoadDataset(dir / "S");
  const std::string before = testing::ReadTextFile(original.train[0].image_path);
  const std::string error = testing::ErrorOf(
      [&] { SynthesizeDatasetLdr(dir / "V", {.crf = "gamma:2.2", .replace_foreign = true}); });
  EXPECT_NE(error.find("is a link into the scene " + (dir / "S").string()), std::string::npos)
      << error;
  EXPECT_EQ(testing::ReadTextFile(original.train[0].image_path), before);
  // A link to a folder of no scene is written through.
  SmallScene(dir / "T");
  fs::create_directories(dir / "T" / "images");
  fs::rename(dir / "T" / "images", dir / "elsewhere");
  fs::create_directory_symlink(dir / "elsewhere", dir / "T" / "images");
  EXPECT_GT(SynthesizeDatasetLdr(dir / "T", {.crf = "filmic"}), 0);
}

// The sweep of session 94: merge-hdr replaced files of an output's name already in --out (a folder
// of renders, named alike, would lose them), and a bad crf_spec in synthesis.json was reported
// without the file.
TEST(ExposureStack, MergeReplacesNoFileUnlessToldAndNamesTheManifest) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  SynthesizeDatasetLdr(dir.path(), {.crf = "filmic"});
  const fs::path kept = dir / "M" / dataset.test[0].hdr_path->filename();
  testing::WriteTextFile(kept, "precious");
  const std::string error =
      testing::ErrorOf([&] { MergeDatasetExposures(dir.path(), dir / "M", {.split = "test"}); });
  EXPECT_NE(error.find(kept.string() + ": exists"), std::string::npos) << error;
  EXPECT_NE(error.find("--overwrite"), std::string::npos) << error;
  EXPECT_EQ(testing::ReadTextFile(kept), "precious");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "M"), fs::directory_iterator()), 1);
  EXPECT_EQ(MergeDatasetExposures(dir.path(), dir / "M", {.split = "test", .overwrite = true}), 2);
  EXPECT_EQ(ReadImage(kept).channels(), 3);

  nlohmann::json manifest = ReadJsonFile(dir / "synthesis.json");
  manifest["crf_spec"] = "gamma:-3";
  WriteJsonFile(dir / "synthesis.json", manifest);
  const std::string bad_crf =
      testing::ErrorOf([&] { MergeDatasetExposures(dir.path(), dir / "N", {.split = "test"}); });
  EXPECT_NE(bad_crf.find((dir / "synthesis.json").string() + ": crf_spec: "), std::string::npos)
      << bad_crf;
}

}  // namespace
}  // namespace hdr4d
