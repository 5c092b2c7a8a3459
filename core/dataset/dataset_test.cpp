#include "core/dataset/dataset.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/geometry/ply.h"
#include "core/dataset/dataset_check_report.h"
#include "core/dataset/scene_profile.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::RandomImage;
using testing::TempDir;

constexpr double kAngle = 0.8;

json Rows(const Eigen::Matrix4d& m) {
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

Eigen::Matrix4d PoseOnRing(int i) {
  const double a = 0.7 * i;
  return LookAtWorldFromCamGl({4 * std::cos(a), 4 * std::sin(a), 1.5}, {0, 0, 0},
                              Eigen::Vector3d::UnitZ());
}

// A scene in the reference layout, written file by file: frames get a PNG (file_path without
// extension, as D-NeRF writes it), an EXR, time = index and exposure 0.5 (index + 1).
class Scene {
 public:
  explicit Scene(const fs::path& root) : root_(root) {
    for (const char* split : {"train", "test"}) {
      files_[split] = {{"camera_angle_x", kAngle}, {"frames", json::array()}};
    }
  }

  json& Add(const std::string& split, int w = 8, int h = 6, bool exr = true) {
    if (!files_.count(split))
      files_[split] = {{"camera_angle_x", kAngle}, {"frames", json::array()}};
    json& frames = files_[split]["frames"];
    const int i = static_cast<int>(frames.size());
    const std::string stem = split + "_" + std::to_string(i);
    json f = {{"file_path", "./images/" + stem},
              {"time", i},
              {"exposures", 0.5 * (i + 1)},
              {"transform_matrix", Rows(PoseOnRing(i + (split == "test" ? 10 : 0)))}};
    WriteImage(root_ / "images" / (stem + ".png"),
               RandomImage(w, h, 3, seed_++, 0, 1, Encoding::kSrgb));
    if (exr) {
      f["exr_file_path"] = "hdr/" + stem + ".exr";
      WriteImage(root_ / "hdr" / (stem + ".exr"), RandomImage(w, h, 3, seed_++, 0, 100));
    }
    frames.push_back(f);
    return frames.back();
  }
  json& File(const std::string& split) { return files_.at(split); }
  json& Frame(const std::string& split, int i) { return files_.at(split)["frames"][i]; }
  void Write() const {
    for (const auto& [split, doc] : files_)
      WriteJsonFile(root_ / ("transforms_" + split + ".json"), doc);
  }
  const fs::path& root() const { return root_; }

 private:
  fs::path root_;
  std::map<std::string, json> files_;
  unsigned seed_ = 1;
};

// 3 train + 2 test frames, all valid.
void AddGoodFrames(Scene& scene) {
  for (int i = 0; i < 3; ++i) scene.Add("train");
  for (int i = 0; i < 2; ++i) scene.Add("test");
}

std::string AllProblems(const DatasetReport& report) {
  std::string s;
  for (const DatasetProblem& p : report.problems) s += "  " + p.ToString() + "\n";
  return s;
}

// True when a problem of `file` (file name), `frame` and `key` has `text` in its message; the
// one-line form must name the file and the frame too.
bool HasProblem(const DatasetReport& report,
                const std::string& file,
                int frame,
                const std::string& key,
                const std::string& text) {
  for (const DatasetProblem& p : report.problems) {
    if (p.file.filename() != file || p.frame != frame || p.key != key) continue;
    if (p.message.find(text) == std::string::npos) continue;
    const std::string line = p.ToString();
    if (line.find(p.file.string()) != 0) return false;
    if (frame >= 0 && line.find("frame " + std::to_string(frame)) == std::string::npos)
      return false;
    return true;
  }
  return false;
}

#define EXPECT_PROBLEM(report, file, frame, key, text)                                \
  EXPECT_TRUE(HasProblem(report, file, frame, key, text))                             \
      << "expected " << file << ": frame " << frame << ": " << key << ": ..." << text \
      << "...\nproblems:\n"                                                           \
      << AllProblems(report)

DatasetReport Check(const Scene& scene, ImageCheck check = ImageCheck::kHeaders) {
  return CheckDataset(scene.root(), {.image_check = check});
}

// ---------------------------------------------------------------------------------------------
// The real D-NeRF lego scene (100x100).

TEST(Dataset, LoadsDnerfLego) {
  const auto root = testing::SharedData("dnerf_lego_tiny");
  if (!root) GTEST_SKIP() << "shared data dnerf_lego_tiny is not available";
  const Dataset d = LoadDataset(*root);
  EXPECT_EQ(d.layout, "dnerf");
  ASSERT_EQ(d.train.size(), 50u);
  EXPECT_EQ(d.test.size(), 20u);
  EXPECT_EQ(d.val.size(), 11u);
  EXPECT_EQ(d.AllFrames().size(), 81u);
  EXPECT_DOUBLE_EQ(d.camera_angle_x, 0.6911112070083618);
  EXPECT_FALSE(d.point_cloud_path.has_value());
  EXPECT_DOUBLE_EQ(d.time_max_raw, 1.0);
  for (const Frame* f : d.AllFrames()) {
    EXPECT_GE(f->time, 0.0);
    EXPECT_LE(f->time, 1.0);
    EXPECT_EQ(f->time, f->time_raw);  // max is 1: nothing to normalise
    EXPECT_FALSE(f->exposure_given);
    EXPECT_EQ(f->exposure, 1.0);
    EXPECT_FALSE(f->hdr_path.has_value());
    EXPECT_EQ(f->camera.intrinsics.width, 100);
    EXPECT_EQ(f->camera.intrinsics.height, 100);
    EXPECT_NEAR(f->camera.intrinsics.fx, 138.889, 1e-3);
    EXPECT_EQ(f->camera.intrinsics.fx, 138.88887889922103);  // fl_x as written
    EXPECT_EQ(f->camera.intrinsics.fy, f->camera.intrinsics.fx);
    EXPECT_EQ(f->camera.intrinsics.cx, 50.0);
  }
  EXPECT_EQ(d.train[0].file_path, "./images/train_000");
  EXPECT_EQ(d.train[0].image_path, *root / "images/train_000.png");
  EXPECT_EQ(d.val[10].image_path, *root / "images/val_010.png");
  EXPECT_EQ(d.train[49].time, 1.0);
  EXPECT_NEAR(d.train[1].time, 0.020202020183205605, 1e-15);
  // First train pose as written.
  EXPECT_NEAR(d.train[0].camera.world_from_cam_gl(0, 3), 2.934088945388794, 1e-15);
  EXPECT_NEAR(d.train[0].camera.Center().norm(), 4.031, 1e-3);  // cameras on a sphere

  const SceneProfile profile = ProfileScene(d);
  EXPECT_TRUE(profile.dynamic);
  EXPECT_FALSE(profile.multi_view);
  EXPECT_FALSE(profile.multi_exposure);
  EXPECT_FALSE(profile.has_hdr_gt);
  EXPECT_FALSE(profile.partial_hdr_gt);
  EXPECT_EQ(profile.exposures, std::vector<double>{1.0});
  EXPECT_EQ(profile.width, 100);
  EXPECT_EQ(profile.height, 100);
  EXPECT_EQ(profile.time_min, 0.0);
  EXPECT_EQ(profile.time_max, 1.0);
  EXPECT_EQ(profile.num_cameras, 71);  // 50 train + 20 test poses; the 11 val frames share one
}

TEST(Dataset, LegoFullDecodeFindsNoProblem) {
  const auto root = testing::SharedData("dnerf_lego_tiny");
  if (!root) GTEST_SKIP() << "shared data dnerf_lego_tiny is not available";
  const DatasetReport report = CheckDataset(*root, {.image_check = ImageCheck::kFull});
  EXPECT_TRUE(report.ok()) << AllProblems(report);
}

// ---------------------------------------------------------------------------------------------
// The reference layout and its quirks.

TEST(Dataset, ReferenceLayoutQuirks) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 1)["file_path"] = "images/train_1.png";  // has an extension: kept
  scene.Frame("train", 2)["exposures"] = json::array({2.0});    // one-element list
  scene.Frame("train", 0).erase("exr_file_path");
  scene.Frame("test", 1)["camera_id"] = 3;
  scene.Frame("test", 1)["exposure_index"] = 2;
  scene.File("train")["near"] = 0.5;
  scene.File("train")["far"] = 7;
  scene.Write();
  const Dataset d = LoadDataset(dir.path());
  EXPECT_EQ(d.layout, "hdr4d");
  ASSERT_EQ(d.train.size(), 3u);
  ASSERT_EQ(d.test.size(), 2u);
  EXPECT_TRUE(d.val.empty());
  EXPECT_EQ(d.train[0].file_path, "./images/train_0");
  EXPECT_EQ(d.train[0].image_path, dir.path() / "images/train_0.png");
  EXPECT_EQ(d.train[1].image_path, dir.path() / "images/train_1.png");
  EXPECT_EQ(d.train[0].split, Split::kTrain);
  EXPECT_EQ(d.test[1].split, Split::kTest);
  EXPECT_EQ(d.test[1].index, 1);
  EXPECT_DOUBLE_EQ(d.train[0].exposure, 0.5);  // scalar
  EXPECT_TRUE(d.train[0].exposure_given);
  EXPECT_DOUBLE_EQ(d.train[2].exposure, 2.0);  // list
  EXPECT_FALSE(d.train[0].hdr_path.has_value());
  ASSERT_TRUE(d.train[1].hdr_path.has_value());
  EXPECT_EQ(*d.train[1].exr_file_path, "hdr/train_1.exr");
  EXPECT_EQ(*d.train[1].hdr_path, dir.path() / "hdr/train_1.exr");
  EXPECT_EQ(d.test[1].camera_id, 3);
  EXPECT_EQ(d.test[1].exposure_index, 2);
  EXPECT_EQ(d.test[0].camera_id, -1);
  EXPECT_EQ(d.near, 0.5);
  EXPECT_EQ(d.far, 7.0);
  // Intrinsics from camera_angle_x at the image's size (8x6).
  const PinholeIntrinsics& k = d.train[0].camera.intrinsics;
  EXPECT_EQ(k.width, 8);
  EXPECT_EQ(k.height, 6);
  EXPECT_DOUBLE_EQ(k.fx, 4.0 / std::tan(0.4));
  EXPECT_DOUBLE_EQ(k.fy, k.fx);
  EXPECT_EQ(k.cx, 4.0);
  EXPECT_EQ(k.cy, 3.0);
  EXPECT_TRUE(d.train[2].camera.world_from_cam_gl.isApprox(PoseOnRing(2)));
  // Times 0,1,2 (train) and 0,1 (test): divided by the global max 2.
  EXPECT_EQ(d.time_max_raw, 2.0);
  EXPECT_EQ(d.train[2].time, 1.0);
  EXPECT_EQ(d.test[1].time, 0.5);
  EXPECT_EQ(d.test[1].time_raw, 1.0);
}

TEST(Dataset, IntrinsicsKeysTopLevelAndPerFrame) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.File("train")["fl_x"] = 10.0;
  scene.File("train")["cy"] = 2.5;
  scene.Frame("train", 1)["fl_x"] = 12.0;
  scene.Frame("train", 1)["fl_y"] = 11.0;
  scene.Frame("train", 2)["cx"] = 4.25;
  scene.Frame("train", 2)["w"] = 8;
  scene.Frame("train", 2)["h"] = 6;
  scene.File("test").erase("camera_angle_x");
  scene.File("test")["fl_x"] = 9.0;
  scene.Write();
  const Dataset d = LoadDataset(dir.path());
  const auto& k0 = d.train[0].camera.intrinsics;
  EXPECT_EQ(k0.fx, 10.0);  // fl_x wins over camera_angle_x
  EXPECT_EQ(k0.fy, 10.0);  // fl_y defaults to fl_x
  EXPECT_EQ(k0.cx, 4.0);
  EXPECT_EQ(k0.cy, 2.5);
  const auto& k1 = d.train[1].camera.intrinsics;
  EXPECT_EQ(k1.fx, 12.0);  // per frame wins
  EXPECT_EQ(k1.fy, 11.0);
  EXPECT_EQ(d.train[2].camera.intrinsics.cx, 4.25);
  EXPECT_EQ(d.test[0].camera.intrinsics.fx, 9.0);  // no camera_angle_x needed with fl_x
  EXPECT_EQ(d.camera_angle_x, kAngle);             // the train file's
}

TEST(Dataset, TimeNormalisationGlobalVersusPerFileReference) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 0)["time"] = 0;
  scene.Frame("train", 1)["time"] = 4;
  scene.Frame("train", 2)["time"] = 10;
  scene.Frame("test", 0)["time"] = 2.5;
  scene.Frame("test", 1)["time"] = 5;
  scene.Write();
  const Dataset global = LoadDataset(dir.path());
  EXPECT_EQ(global.time_max_raw, 10.0);
  EXPECT_DOUBLE_EQ(global.train[1].time, 0.4);
  EXPECT_DOUBLE_EQ(global.train[2].time, 1.0);
  EXPECT_DOUBLE_EQ(global.test[0].time, 0.25);
  EXPECT_DOUBLE_EQ(global.test[1].time, 0.5);
  EXPECT_EQ(global.test[1].time_raw, 5.0);

  const Dataset reference =
      LoadDataset(dir.path(), {.time_normalisation = TimeNormalisation::kPerFileReference});
  EXPECT_DOUBLE_EQ(reference.train[1].time, 0.4);
  EXPECT_DOUBLE_EQ(reference.test[0].time, 0.5);  // 2.5 / 5: misaligned with train
  EXPECT_DOUBLE_EQ(reference.test[1].time, 1.0);
  EXPECT_EQ(reference.test[1].time_raw, 5.0);
}

TEST(Dataset, ValSplitJoinsTheGlobalTimeMaximum) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Add("val");
  scene.Frame("val", 0)["time"] = 20;
  scene.Write();
  const Dataset d = LoadDataset(dir.path());
  ASSERT_EQ(d.val.size(), 1u);
  EXPECT_EQ(d.val[0].split, Split::kVal);
  EXPECT_EQ(d.time_max_raw, 20.0);
  EXPECT_DOUBLE_EQ(d.train[2].time, 0.1);
  EXPECT_EQ(d.AllFrames().back(), &d.val[0]);
  EXPECT_STREQ(SplitName(Split::kVal), "val");
}

TEST(Dataset, ResolveImagePathAppendsPngOnlyWithoutAnImageExtension) {
  const fs::path root = "/data/scene";
  EXPECT_EQ(ResolveImagePath(root, "./train/r_000"), "/data/scene/train/r_000.png");
  EXPECT_EQ(ResolveImagePath(root, "a/b.png"), "/data/scene/a/b.png");
  EXPECT_EQ(ResolveImagePath(root, "a/b.JPG"), "/data/scene/a/b.JPG");
  EXPECT_EQ(ResolveImagePath(root, "a/b.jpeg"), "/data/scene/a/b.jpeg");
  EXPECT_EQ(ResolveImagePath(root, "a/b.exr"), "/data/scene/a/b.exr");
  EXPECT_EQ(ResolveImagePath(root, "a/frame.001"),
            "/data/scene/a/frame.001.png");  // not an image ext
}

TEST(Dataset, NoneCheckReadsNoImagesWhenSizesAreDeclared) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.File("train")["w"] = 8;
  scene.File("train")["h"] = 6;
  scene.File("test")["w"] = 8;
  scene.File("test")["h"] = 6;
  scene.Write();
  fs::remove_all(dir / "images");  // synth-ldr writes them later
  const DatasetReport report = CheckDataset(dir.path(), {.image_check = ImageCheck::kNone});
  EXPECT_TRUE(report.ok()) << AllProblems(report);
  EXPECT_EQ(report.dataset->train[0].camera.intrinsics.width, 8);
  // Headers mode finds the missing images.
  EXPECT_EQ(CheckDataset(dir.path()).problems.size(), 5u);
}

TEST(Dataset, NoneCheckSizesCamerasFromTheHdrImageWhenLdrIsMissing) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  fs::remove_all(dir / "images");
  const DatasetReport report = CheckDataset(dir.path(), {.image_check = ImageCheck::kNone});
  ASSERT_TRUE(report.ok()) << AllProblems(report);
  for (const Frame* f : report.dataset->AllFrames()) {
    EXPECT_EQ(f->camera.intrinsics.width, 8);
    EXPECT_EQ(f->camera.intrinsics.height, 6);
  }
  fs::remove_all(dir / "hdr");
  const DatasetReport none = CheckDataset(dir.path(), {.image_check = ImageCheck::kNone});
  EXPECT_EQ(none.problems.size(), 1u) << AllProblems(none);  // once, not for every frame
  EXPECT_PROBLEM(none, "transforms_train.json", 0, "file_path", "cannot size the camera");
}

TEST(Dataset, PointCloudRecordedAndCounted) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  PointCloud cloud;
  for (int i = 0; i < 5; ++i) cloud.positions.emplace_back(i, 0, 0);
  WritePly(dir / "point3d.ply", cloud);
  const DatasetReport report = CheckDataset(dir.path());
  ASSERT_TRUE(report.ok()) << AllProblems(report);
  EXPECT_EQ(report.dataset->point_cloud_path, dir / "point3d.ply");
  EXPECT_EQ(report.point_cloud_points, 5);

  testing::WriteTextFile(dir / "point3d.ply", "ply\nformat ascii 1.0\nelement vertex 2\n");
  const DatasetReport bad = CheckDataset(dir.path());
  EXPECT_PROBLEM(bad, "point3d.ply", -1, "", "no end_header");
  EXPECT_FALSE(bad.point_cloud_points.has_value());
}

TEST(Dataset, HdrNerfSyntheticLayoutExpandsExposures) {
  TempDir dir;
  const double exposures[5] = {0.125, 0.5, 2.0, 8.0, 32.0};
  unsigned seed = 1;
  for (const char* split : {"train", "test"}) {
    json doc = {{"camera_angle_x", kAngle}, {"frames", json::array()}};
    json table = json::object();
    for (int v = 0; v < 2; ++v) {
      const std::string fp = std::string("./") + split + "/r_" + std::to_string(v);
      doc["frames"].push_back({{"file_path", fp}, {"transform_matrix", Rows(PoseOnRing(v))}});
      for (int k = 0; k < 5; ++k) {
        const std::string name = fp + "_" + std::to_string(k) + ".png";
        table[name] = exposures[k];
        WriteImage(dir / name, RandomImage(6, 4, 3, seed++, 0, 1, Encoding::kSrgb));
      }
    }
    WriteJsonFile(dir / (std::string("transforms_") + split + ".json"), doc);
    WriteJsonFile(dir / (std::string("exposure_") + split + ".json"), table);
  }
  const Dataset d = LoadDataset(dir.path());
  EXPECT_EQ(d.layout, "hdrnerf");
  ASSERT_EQ(d.train.size(), 10u);
  ASSERT_EQ(d.test.size(), 10u);
  EXPECT_EQ(d.train[7].file_path, "./train/r_1_2.png");
  EXPECT_EQ(d.train[7].image_path, dir / "train/r_1_2.png");
  EXPECT_EQ(d.train[7].index, 1);
  EXPECT_EQ(d.train[7].exposure_index, 2);
  EXPECT_EQ(d.train[7].exposure, 2.0);
  EXPECT_EQ(d.train[7].time, 0.0);
  const SceneProfile profile = ProfileScene(d);
  EXPECT_FALSE(profile.dynamic);
  EXPECT_TRUE(profile.multi_exposure);
  EXPECT_EQ(profile.exposures.size(), 5u);
  EXPECT_TRUE(profile.multi_view);  // several poses at the one instant

  // A view without exposures and a bad exposure value name the exposure file.
  json table = ReadJsonFile(dir / "exposure_train.json");
  table.erase("./train/r_1_0.png");
  table.erase("./train/r_1_1.png");
  table.erase("./train/r_1_2.png");
  table.erase("./train/r_1_3.png");
  table.erase("./train/r_1_4.png");
  table["./train/r_0_3.png"] = -1;
  WriteJsonFile(dir / "exposure_train.json", table);
  const DatasetReport report = CheckDataset(dir.path());
  EXPECT_PROBLEM(report, "exposure_train.json", 1, "./train/r_1_0.png",
                 "no exposure for this view");
  EXPECT_PROBLEM(report, "exposure_train.json", 0, "./train/r_0_3.png",
                 "must be positive and finite, got -1");

  // The sweep of session 94: a gap in a view's exposure indices dropped the later exposures
  // without a word, and --exposure-unit stops was not applied to the exposure files.
  table["./train/r_0_3.png"] = 8.0;
  table.erase("./train/r_0_1.png");
  WriteJsonFile(dir / "exposure_train.json", table);
  const DatasetReport gap = CheckDataset(dir.path());
  EXPECT_PROBLEM(gap, "exposure_train.json", 0, "./train/r_0_1.png",
                 "missing, while ./train/r_0_4.png is given");
  for (const char* split : {"train", "test"}) {
    json stops = ReadJsonFile(dir / (std::string("exposure_") + split + ".json"));
    for (auto& [name, value] : stops.items()) value = std::log2(value.get<double>());
    if (std::string(split) == "train") {
      stops["./train/r_0_1.png"] = -1.0;
      for (int k = 0; k < 5; ++k) stops["./train/r_1_" + std::to_string(k) + ".png"] = k - 3;
    }
    WriteJsonFile(dir / (std::string("exposure_") + split + ".json"), stops);
  }
  const Dataset in_stops = LoadDataset(dir.path(), {.exposure_unit = ExposureUnit::kStops});
  EXPECT_EQ(in_stops.train[7].exposure, 0.5);  // view 1, k = 2: 2^-1 s
  EXPECT_EQ(in_stops.train[1].exposure, 0.5);  // view 0, k = 1: 2^-1 s
  EXPECT_EQ(in_stops.test[4].exposure, 32.0);
}

// ---------------------------------------------------------------------------------------------
// Broken scenes: each problem names the file, the frame and the key.

TEST(DatasetProblems, MissingImage) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  fs::remove(dir / "images/test_1.png");
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_test.json", 1, "file_path", "file not found");
  EXPECT_NE(report.problems[0].message.find("images/test_1.png"), std::string::npos);
  EXPECT_TRUE(report.dataset.has_value());  // parsed far enough for a summary
}

TEST(DatasetProblems, NanAndInfPixelsInExrFoundByFullCheck) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  Image nan_image = RandomImage(8, 6, 3, 9, 0, 10);
  nan_image.at(3, 2, 1) = std::numeric_limits<float>::quiet_NaN();
  WriteImage(dir / "hdr/train_1.exr", nan_image, {.format = PixelFormat::kFloat});
  Image inf_image = RandomImage(8, 6, 3, 9, 0, 10);
  inf_image.at(5, 4, 0) = std::numeric_limits<float>::infinity();
  WriteImage(dir / "hdr/test_0.exr", inf_image, {.format = PixelFormat::kFloat});

  EXPECT_TRUE(Check(scene, ImageCheck::kHeaders).ok());  // headers cannot see pixels
  const DatasetReport report = Check(scene, ImageCheck::kFull);
  EXPECT_EQ(report.problems.size(), 2u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", 1, "exr_file_path",
                 "non-finite pixel value (nan) at x=3, y=2");
  EXPECT_PROBLEM(report, "transforms_test.json", 0, "exr_file_path",
                 "non-finite pixel value (inf) at x=5, y=4");
}

// Issue 11, case 10: `dataset check --full` must find everything training refuses. Negative
// radiance in an HDR image, and an HDR image (here with a NaN) given as a frame's file_path,
// used to pass it.
TEST(DatasetProblems, FullCheckFindsWhatTrainingRefuses) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  Image negative = RandomImage(8, 6, 3, 9, 0, 10);
  negative.at(1, 2, 2) = -0.5f;
  WriteImage(dir / "hdr/train_1.exr", negative, {.format = PixelFormat::kFloat});
  Image nan_image = RandomImage(8, 6, 3, 10, 0, 10);
  nan_image.at(4, 3, 0) = std::numeric_limits<float>::quiet_NaN();
  WriteImage(dir / "hdr/as_ldr.exr", nan_image, {.format = PixelFormat::kFloat});
  scene.Frame("test", 1)["file_path"] = "hdr/as_ldr.exr";
  WriteImage(dir / "hdr/black.exr", Image(8, 6, 3), {.format = PixelFormat::kFloat});
  scene.Frame("train", 2)["exr_file_path"] = "hdr/black.exr";
  scene.Write();

  const DatasetReport full = Check(scene, ImageCheck::kFull);
  EXPECT_EQ(full.problems.size(), 3u) << AllProblems(full);
  EXPECT_PROBLEM(full, "transforms_train.json", 1, "exr_file_path",
                 "negative radiance -0.5 at x=1, y=2, channel 2");
  EXPECT_PROBLEM(full, "transforms_test.json", 1, "file_path", "non-finite pixel value (nan)");
  EXPECT_PROBLEM(full, "transforms_train.json", 2, "exr_file_path", "has no positive value");
  // The header says the file_path image is float: found without decoding it.
  const DatasetReport headers = Check(scene, ImageCheck::kHeaders);
  EXPECT_EQ(headers.problems.size(), 1u) << AllProblems(headers);
  EXPECT_PROBLEM(headers, "transforms_test.json", 1, "file_path", "is a linear HDR image");
  EXPECT_THROW(LoadDataset(dir.path()), Error);  // what train loads with
}

TEST(DatasetProblems, GroundTruthThatIsNotHdrOrNotRgbIsAProblem) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  WriteImage(dir / "hdr/grey.exr", Image(8, 6, 1, Encoding::kLinear, 1.0f));
  scene.Frame("train", 0)["exr_file_path"] = "hdr/grey.exr";
  scene.Frame("test", 0)["exr_file_path"] = "images/test_1.png";
  scene.Write();
  const DatasetReport report = Check(scene, ImageCheck::kHeaders);
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "exr_file_path", "HDR ground truth needs RGB");
  EXPECT_PROBLEM(report, "transforms_test.json", 0, "exr_file_path",
                 "exr_file_path must be linear HDR radiance");
}

// Reading a scene inside a command protects it from that command's writers: its files and the
// folders that hold its images (issue 11, case 1).
TEST(Dataset, ReadingASceneProtectsItsFilesAndImageFolders) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  const InputProtectionScope command;
  ASSERT_TRUE(Check(scene).ok());
  for (const fs::path& p : {dir / "images" / "train_0.png", dir / "images" / "new.png",
                            dir / "hdr" / "test_1.exr", dir / "transforms_test.json"}) {
    EXPECT_THROW(CheckOutput(p), Error) << p;
  }
  EXPECT_NO_THROW(CheckOutput(dir / "results.json"));
  EXPECT_NO_THROW(CheckOutput(dir / "renders" / "train_0.png"));
}

TEST(DatasetProblems, MissingTime) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 2).erase("time");
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "time", "missing");
}

TEST(DatasetProblems, NegativeTime) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("test", 0)["time"] = -0.5;
  scene.Write();
  EXPECT_PROBLEM(Check(scene), "transforms_test.json", 0, "time", "must not be negative");
}

TEST(DatasetProblems, OverflowingNumberIsAFileProblem) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  // JSON has no NaN/Inf literal; 1e999 is the nearest thing and the parser refuses it.
  std::string text = testing::ReadTextFile(dir / "transforms_train.json");
  const std::string needle = "\"time\": 1";
  ASSERT_NE(text.find(needle), std::string::npos);
  text.replace(text.find(needle), needle.size(), "\"time\": 1e999");
  testing::WriteTextFile(dir / "transforms_train.json", text);
  const DatasetReport report = Check(scene);
  EXPECT_PROBLEM(report, "transforms_train.json", -1, "", "number overflow parsing '1e999'");
  EXPECT_FALSE(report.dataset.has_value());
}

TEST(DatasetProblems, MissingTransformMatrix) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 0).erase("transform_matrix");
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "transform_matrix", "missing");
}

TEST(DatasetProblems, WrongJsonTypes) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 1)["time"] = "abc";
  scene.Frame("train", 2)["file_path"] = 42;
  scene.Frame("test", 0)["transform_matrix"] = json::array({1, 2, 3});
  scene.Frame("test", 1)["camera_id"] = 1.5;
  scene.File("test")["camera_angle_x"] = "wide";
  scene.Frame("train", 0)["exr_file_path"] = "";
  scene.Frame("train", 0)["fl_x"] = -3;
  scene.Frame("train", 0)["w"] = 0;
  scene.Frame("test", 0)["exposure_index"] = -1;
  scene.File("test")["frames"].push_back(7);
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "exr_file_path", "is empty");
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "fl_x", "must be positive, got -3");
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "w", "must be at least 1, got 0");
  EXPECT_PROBLEM(report, "transforms_test.json", 0, "exposure_index", "must be at least 0, got -1");
  EXPECT_PROBLEM(report, "transforms_test.json", 2, "", "expected a JSON object, got number 7");
  EXPECT_PROBLEM(report, "transforms_train.json", 1, "time",
                 "expected a number, got string \"abc\"");
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "file_path",
                 "expected a string, got number 42");
  EXPECT_PROBLEM(report, "transforms_test.json", 0, "transform_matrix",
                 "expected a 4x4 array of numbers");
  EXPECT_PROBLEM(report, "transforms_test.json", 1, "camera_id", "expected an integer");
  EXPECT_PROBLEM(report, "transforms_test.json", -1, "camera_angle_x", "expected a number");
}

TEST(DatasetProblems, ZeroAndNegativeExposure) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 0)["exposures"] = 0;
  scene.Frame("test", 1)["exposures"] = -2;
  scene.Frame("train", 2)["exposures"] = json::array({1, 2});
  scene.Write();
  const DatasetReport report = Check(scene);
  // The three, and (all small, 0 and -2 not positive) that they may be log2 stops.
  EXPECT_EQ(report.problems.size(), 4u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", -1, "exposures", "look like log2 stops");
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "exposures",
                 "must be positive and finite, got 0");
  EXPECT_PROBLEM(report, "transforms_test.json", 1, "exposures",
                 "must be positive and finite, got -2");
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "exposures", "expected a number");
}

// The sweep of session 94: one frame without `exposures` among frames with it was read as 1 s,
// and `dataset check` said "no problems". A scene where no frame has one is D-NeRF's layout.
TEST(DatasetProblems, AFrameWithoutTheExposureOthersGiveIsAProblem) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("test", 1).erase("exposures");
  scene.Frame("train", 2)["exposures"] = "long";  // present: its own problem, not "missing"
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 2u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_test.json", 1, "exposures",
                 "missing, while 4 of the scene's 5 frames give one (it would be read as 1 s)");
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "exposures", "expected a number");

  TempDir none;
  Scene dnerf(none.path());
  AddGoodFrames(dnerf);
  for (const char* split : {"train", "test"})
    for (json& f : dnerf.File(split)["frames"]) f.erase("exposures");
  dnerf.Write();
  EXPECT_TRUE(Check(dnerf).problems.empty()) << AllProblems(Check(dnerf));
}

// The sweep of session 94: a test frame naming a training frame's image at another exposure
// passed `dataset check` (synth-ldr wrote the file twice, the last write winning), and so did
// one HDR image for frames of different times (merge-hdr fused them).
TEST(DatasetProblems, AnImageOfTwoSplitsAndAnHdrImageOfTwoTimesAreProblems) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("test", 0)["file_path"] = scene.Frame("train", 1)["file_path"];
  scene.Frame("train", 2)["exr_file_path"] = scene.Frame("train", 0)["exr_file_path"];
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 2u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_test.json", 0, "file_path",
                 "is also frame 1 of transforms_train.json at another exposure (1 s there, "
                 "0.5 s here)");
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "exr_file_path",
                 "is also the HDR image of frame 0 of transforms_train.json, which shows another "
                 "pose (time 0 there, 2 here)");
  // Frames of one view at one time (an exposure bracket) share their HDR image.
  TempDir bracket_dir;
  Scene bracket(bracket_dir.path());
  AddGoodFrames(bracket);
  json& second = bracket.Add("train");
  second["transform_matrix"] = bracket.Frame("train", 0)["transform_matrix"];
  second["time"] = bracket.Frame("train", 0)["time"];
  second["exr_file_path"] = bracket.Frame("train", 0)["exr_file_path"];
  bracket.Write();
  EXPECT_TRUE(Check(bracket).problems.empty()) << AllProblems(Check(bracket));
}

// HDR-HexPlane's dataset/lego layout (its first commit): near/far,
// integer frame times and `exposures` as log2 stops (-3, -1, 1) under HDR-4DGS's key. A fixture
// in that layout, written here.
Scene HexPlaneStyleScene(const fs::path& root) {
  Scene scene(root);
  const int stops[3] = {-1, 1, -3};
  for (const char* split : {"train", "test"}) {
    scene.File(split)["near"] = 2;
    scene.File(split)["far"] = 15;
    for (int i = 0; i < 3; ++i) {
      json& f = scene.Add(split, 8, 6, /*exr=*/false);
      f["exposures"] = stops[i];
      f["time"] = std::string(split) == "train" ? i + 1 : 5 * i;
    }
  }
  scene.Write();
  return scene;
}

TEST(DatasetExposureUnit, StopsReadAsSecondsAreRecognisedWithTheFix) {
  TempDir dir;
  const Scene scene = HexPlaneStyleScene(dir.path());
  const DatasetReport report = Check(scene);
  EXPECT_PROBLEM(report, "transforms_train.json", -1, "exposures",
                 "all 6 exposures are small (in [-3, 1]) and 4 not positive: they look like "
                 "log2 stops");
  EXPECT_PROBLEM(report, "transforms_train.json", -1, "exposures",
                 "--exposure-unit stops (seconds = 2**value: -3 -> 0.125 s, 1 -> 2 s)");
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "exposures", "must be positive");
  EXPECT_EQ(report.problems.size(), 5u) << AllProblems(report);
  ASSERT_TRUE(report.dataset);
  EXPECT_TRUE(report.dataset->exposures_look_like_stops);
  // The summary never calls +1 stop "1 s": the written values, said to be unread.
  const std::string text = DatasetReportText(report);
  EXPECT_NE(text.find("exposures:   not read: written as -3, -1, 1 (log2 stops?"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("1 s"), std::string::npos) << text;
  EXPECT_NE(text.find("exposures: not read (they look like log2 stops"), std::string::npos)
      << text;
  const json summary = DatasetReportJson(report)["summary"];
  EXPECT_EQ(summary["exposures_written"], json({-3.0, -1.0, 1.0}));
  EXPECT_TRUE(summary["exposures_look_like_stops"].get<bool>());
}

TEST(DatasetExposureUnit, StopsLoadAsTwoToTheValueSeconds) {
  TempDir dir;
  const Scene scene = HexPlaneStyleScene(dir.path());
  const DatasetReport report = CheckDataset(
      scene.root(), {.image_check = ImageCheck::kHeaders, .exposure_unit = ExposureUnit::kStops});
  ASSERT_TRUE(report.ok()) << AllProblems(report);
  const Dataset& d = *report.dataset;
  EXPECT_EQ(d.exposure_unit, ExposureUnit::kStops);
  EXPECT_FALSE(d.exposures_look_like_stops);
  EXPECT_EQ(d.train[0].exposure, 0.5);
  EXPECT_EQ(d.train[1].exposure, 2.0);
  EXPECT_EQ(d.train[2].exposure, 0.125);
  EXPECT_EQ(*d.train[2].exposure_written, -3.0);
  EXPECT_TRUE(d.train[2].exposure_given);
  EXPECT_EQ(*d.near, 2.0);
  EXPECT_DOUBLE_EQ(d.test[2].time, 1.0);  // times 1..3 and 0, 5, 10: divided by 10
  const std::string text = DatasetReportText(report);
  EXPECT_NE(text.find("exposures:   3 distinct (0.125, 0.5, 2 s; written as -3, -1, 1 stops)"),
            std::string::npos)
      << text;
  EXPECT_EQ(ParseExposureUnit("stops", "t"), ExposureUnit::kStops);
  EXPECT_NE(testing::ErrorOf([] { ParseExposureUnit("ev", "dataset check"); }).find("seconds or stops"),
            std::string::npos);
}

TEST(DatasetExposureUnit, StopsOutOfRangeAndSmallSecondsWithoutNegatives) {
  TempDir dir;
  {
    const Scene scene = HexPlaneStyleScene(dir / "a");
    json doc = ReadJsonFile(dir / "a/transforms_test.json");
    doc["frames"][1]["exposures"] = 1e6;
    WriteJsonFile(dir / "a/transforms_test.json", doc);
    const DatasetReport report = CheckDataset(dir / "a", {.exposure_unit = ExposureUnit::kStops});
    EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
    EXPECT_PROBLEM(report, "transforms_test.json", 1, "exposures", "not a finite number within");
  }
  // Seconds with a lone 0 (a typo, not stops): refused without the stops diagnosis.
  Scene scene(dir / "b");
  AddGoodFrames(scene);
  scene.Frame("train", 1)["exposures"] = 0;
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_FALSE(report.dataset->exposures_look_like_stops);
}

TEST(DatasetProblems, SingularMatrix) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(2, 2) = 0;
  scene.Frame("train", 1)["transform_matrix"] = Rows(m);
  scene.Write();
  EXPECT_PROBLEM(Check(scene), "transforms_train.json", 1, "transform_matrix", "singular");
}

TEST(DatasetProblems, NonRigidMatrix) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  Eigen::Matrix4d m = PoseOnRing(1);
  m.topLeftCorner<3, 3>() *= 1.5;
  scene.Frame("test", 1)["transform_matrix"] = Rows(m);
  Eigen::Matrix4d bottom = PoseOnRing(2);
  bottom(3, 1) = 1;
  scene.Frame("train", 2)["transform_matrix"] = Rows(bottom);
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_PROBLEM(report, "transforms_test.json", 1, "transform_matrix", "not a rotation");
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "transform_matrix", "bottom row");
}

TEST(DatasetProblems, SizeMismatchBetweenFrames) {
  TempDir dir;
  Scene scene(dir.path());
  scene.Add("train", 10, 6, /*exr=*/false);  // the odd one comes first
  scene.Add("train");
  scene.Add("test");
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", 0, "file_path",
                 "image is 10x6, but most images are 8x6 (e.g. frame 1 of transforms_train.json)");
}

TEST(DatasetProblems, SizeMismatchWithDeclaredSize) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.File("test")["w"] = 16;
  scene.File("test")["h"] = 6;
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_PROBLEM(report, "transforms_test.json", 0, "file_path",
                 "image is 8x6, but w, h declare 16x6");
  EXPECT_PROBLEM(report, "transforms_test.json", 1, "file_path",
                 "image is 8x6, but w, h declare 16x6");
}

TEST(DatasetProblems, HdrSizeDiffersFromLdr) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  WriteImage(dir / "hdr/train_2.exr", RandomImage(4, 3, 3, 5, 0, 10));
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "exr_file_path",
                 "HDR image is 4x3, its LDR image");

  // Without its LDR image the HDR image is compared with the scene's size.
  fs::remove(dir / "images/train_2.png");
  const DatasetReport no_ldr = Check(scene);
  EXPECT_EQ(no_ldr.problems.size(), 2u) << AllProblems(no_ldr);
  EXPECT_PROBLEM(no_ldr, "transforms_train.json", 2, "file_path", "file not found");
  EXPECT_PROBLEM(no_ldr, "transforms_train.json", 2, "exr_file_path",
                 "HDR image is 4x3, expected 8x6");
}

TEST(DatasetProblems, CorruptImages) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  // Not an image at all: the header check finds it.
  testing::WriteTextFile(dir / "images/train_0.png", "this is not a PNG file");
  // A real PNG cut short: its header reads, its pixels do not.
  WriteImage(dir / "images/test_0.png", RandomImage(8, 6, 3, 77, 0, 1, Encoding::kSrgb));
  std::string png = testing::ReadTextFile(dir / "images/test_0.png");
  png.resize(png.size() / 2);
  testing::WriteTextFile(dir / "images/test_0.png", png);

  const DatasetReport headers = Check(scene, ImageCheck::kHeaders);
  EXPECT_PROBLEM(headers, "transforms_train.json", 0, "file_path", "cannot read image");
  EXPECT_FALSE(HasProblem(headers, "transforms_test.json", 0, "file_path", ""));
  const DatasetReport full = Check(scene, ImageCheck::kFull);
  EXPECT_PROBLEM(full, "transforms_train.json", 0, "file_path", "cannot read image");
  EXPECT_PROBLEM(full, "transforms_test.json", 0, "file_path", "");
  EXPECT_EQ(full.problems.size(), 2u) << AllProblems(full);
}

TEST(DatasetProblems, InvalidJsonSyntaxGivesLineAndColumn) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  testing::WriteTextFile(dir / "transforms_test.json",
                         "{\n  \"camera_angle_x\": 0.8,\n  \"frames\": [,]\n}\n");
  const DatasetReport report = Check(scene);
  EXPECT_PROBLEM(report, "transforms_test.json", -1, "", "invalid JSON");
  EXPECT_PROBLEM(report, "transforms_test.json", -1, "", "line 3, column 14");
  // Train parsed: the dataset is still summarised.
  ASSERT_TRUE(report.dataset.has_value());
  EXPECT_EQ(report.dataset->train.size(), 3u);
}

TEST(DatasetProblems, MissingTrainJson) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  fs::remove(dir / "transforms_train.json");
  const DatasetReport report = Check(scene);
  ASSERT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", -1, "", "file not found");
  EXPECT_FALSE(report.dataset.has_value());
  try {
    LoadDataset(dir.path());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(
        std::string(e.what()).find((dir / "transforms_train.json").string() + ": file not found"),
        std::string::npos)
        << e.what();
  }
}

TEST(DatasetProblems, MissingTestJsonUnlessAllowed) {
  TempDir dir;
  Scene scene(dir.path());
  scene.Add("train");
  scene.Write();
  fs::remove(dir / "transforms_test.json");
  EXPECT_PROBLEM(Check(scene), "transforms_test.json", -1, "", "file not found");
  const DatasetReport relaxed = CheckDataset(dir.path(), {.require_test = false});
  EXPECT_TRUE(relaxed.ok()) << AllProblems(relaxed);
  EXPECT_TRUE(relaxed.dataset->test.empty());
}

TEST(DatasetProblems, FileLevelProblems) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.File("train").erase("camera_angle_x");
  scene.File("test")["frames"] = json::array();  // an empty test split is allowed
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", -1, "camera_angle_x",
                 "missing, and frame 0 gives no fl_x");

  scene.File("train")["camera_angle_x"] = kAngle;
  scene.File("train")["frames"] = json::array();
  scene.File("test")["frames"] = json::object();
  scene.Write();
  const DatasetReport empty = Check(scene);
  EXPECT_PROBLEM(empty, "transforms_train.json", -1, "frames", "no frames");
  EXPECT_PROBLEM(empty, "transforms_test.json", -1, "frames", "expected an array, got object");

  testing::WriteTextFile(dir / "transforms_test.json", "[1, 2]");
  EXPECT_PROBLEM(Check(scene), "transforms_test.json", -1, "", "expected a JSON object");
  testing::WriteTextFile(dir / "transforms_test.json", "{\"camera_angle_x\": 4}");
  const DatasetReport no_frames = Check(scene);
  EXPECT_PROBLEM(no_frames, "transforms_test.json", -1, "frames", "missing");
  EXPECT_PROBLEM(no_frames, "transforms_test.json", -1, "camera_angle_x", "is not in (0, pi)");
}

TEST(DatasetProblems, DuplicateFilePathsWithinASplit) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 2)["file_path"] = "images/train_0.png";  // same image as frame 0
  scene.Frame("test", 0)["file_path"] = "images/train_0";       // across splits: allowed at
  scene.Frame("test", 0)["exposures"] = 0.5;                     // the same exposure
  scene.Write();
  const DatasetReport report = Check(scene);
  EXPECT_EQ(report.problems.size(), 1u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms_train.json", 2, "file_path", "already used by frame 0");
}

TEST(DatasetProblems, UnsupportedLayoutsAndMissingRoot) {
  TempDir dir;
  fs::create_directories(dir / "colmap/sparse/0");
  const DatasetReport colmap = CheckDataset(dir / "colmap");
  EXPECT_PROBLEM(colmap, "colmap", -1, "", "COLMAP layout needs images/");
  testing::WriteTextFile(dir / "llff/poses_bounds_exps.npy", "x");
  EXPECT_PROBLEM(CheckDataset(dir / "llff"), "llff", -1, "", "LLFF layout");
  EXPECT_PROBLEM(CheckDataset(dir / "nothing"), "nothing", -1, "", "folder not found");
  testing::WriteTextFile(dir / "file", "x");
  EXPECT_PROBLEM(CheckDataset(dir / "file"), "file", -1, "", "not a folder");
}

TEST(DatasetProblems, EveryProblemIsReportedAndLoadThrowsWithAll) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("test", 1)["exposures"] = 0;
  scene.Frame("train", 2).erase("time");
  scene.Write();
  fs::remove(dir / "images/train_0.png");
  const DatasetReport report = Check(scene);
  ASSERT_EQ(report.problems.size(), 3u) << AllProblems(report);
  // Sorted by file (train, then test), then frame.
  EXPECT_EQ(report.problems[0].frame, 0);
  EXPECT_EQ(report.problems[0].key, "file_path");
  EXPECT_EQ(report.problems[1].frame, 2);
  EXPECT_EQ(report.problems[1].key, "time");
  EXPECT_EQ(report.problems[2].file.filename(), "transforms_test.json");
  EXPECT_EQ(report.problems[2].key, "exposures");
  try {
    LoadDataset(dir.path());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    // One line: the first problem, how many more, and the command that lists them all.
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(report.problems[0].ToString()), std::string::npos) << message;
    EXPECT_NE(message.find("and 2 more problems"), std::string::npos) << message;
    EXPECT_NE(message.find("hdr4d dataset check"), std::string::npos) << message;
  }
}

TEST(DatasetProblems, LoadErrorNamesTheFirstAndCountsTheRest) {
  TempDir dir;
  Scene scene(dir.path());
  for (int i = 0; i < 12; ++i) scene.Add("train", 8, 6, false);
  scene.Add("test", 8, 6, false);
  for (int i = 0; i < 12; ++i) scene.Frame("train", i)["exposures"] = -1;
  scene.Write();
  try {
    LoadDataset(dir.path());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    // First the file's own problem: -1 everywhere looks like log2 stops (then 12 frames).
    const std::string message = e.what();
    EXPECT_NE(message.find("exposures: all 13 exposures are small"), std::string::npos)
        << message;
    EXPECT_EQ(message.find("frame 0: exposures"), std::string::npos) << message;
    EXPECT_NE(message.find("and 12 more problems"), std::string::npos) << message;
  }
}

TEST(DatasetProblems, ProblemToString) {
  EXPECT_EQ((DatasetProblem{"/a/t.json", 3, "time", "missing"}).ToString(),
            "/a/t.json: frame 3: time: missing");
  EXPECT_EQ((DatasetProblem{"/a/t.json", -1, "", "file not found"}).ToString(),
            "/a/t.json: file not found");
  EXPECT_EQ((DatasetProblem{"/a/t.json", -1, "frames", "missing"}).ToString(),
            "/a/t.json: frames: missing");
}

// ---------------------------------------------------------------------------------------------
// Writer.

void CopyImages(const fs::path& from, const fs::path& to) {
  for (const char* folder : {"images", "hdr"}) {
    if (fs::exists(from / folder))
      fs::copy(from / folder, to / folder, fs::copy_options::recursive);
  }
}

void ExpectSameFrames(const std::vector<Frame>& a,
                      const std::vector<Frame>& b,
                      const fs::path& root_a,
                      const fs::path& root_b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(a[i].file_path);
    EXPECT_EQ(a[i].split, b[i].split);
    EXPECT_EQ(a[i].index, b[i].index);
    EXPECT_EQ(a[i].file_path, b[i].file_path);
    EXPECT_EQ(a[i].image_path.lexically_relative(root_a),
              b[i].image_path.lexically_relative(root_b));
    EXPECT_EQ(a[i].exr_file_path, b[i].exr_file_path);
    EXPECT_EQ(a[i].time_raw, b[i].time_raw);
    EXPECT_EQ(a[i].time, b[i].time);
    EXPECT_EQ(a[i].exposure, b[i].exposure);
    EXPECT_EQ(a[i].exposure_given, b[i].exposure_given);
    EXPECT_EQ(a[i].camera_id, b[i].camera_id);
    EXPECT_EQ(a[i].exposure_index, b[i].exposure_index);
    EXPECT_EQ(a[i].camera.world_from_cam_gl, b[i].camera.world_from_cam_gl);
    const PinholeIntrinsics& ka = a[i].camera.intrinsics;
    const PinholeIntrinsics& kb = b[i].camera.intrinsics;
    EXPECT_EQ(ka.width, kb.width);
    EXPECT_EQ(ka.height, kb.height);
    EXPECT_NEAR(ka.fx, kb.fx, 1e-9 * ka.fx);
    EXPECT_NEAR(ka.fy, kb.fy, 1e-9 * ka.fy);
    EXPECT_EQ(ka.cx, kb.cx);
    EXPECT_EQ(ka.cy, kb.cy);
  }
}

TEST(DatasetWriter, RoundTripReferenceLayout) {
  TempDir dir;
  Scene scene(dir / "a");
  AddGoodFrames(scene);
  scene.Add("val");
  // A scene without exposures (D-NeRF's layout): the writer writes none either.
  for (const char* split : {"train", "test", "val"})
    for (json& f : scene.File(split)["frames"]) f.erase("exposures");
  scene.Frame("train", 1)["camera_id"] = 4;
  scene.Frame("train", 1)["exposure_index"] = 0;
  scene.Frame("test", 0)["fl_x"] = 7.5;  // per-frame intrinsics survive
  scene.Frame("test", 0)["cy"] = 2.0;
  scene.File("train")["near"] = 0.1;
  scene.Write();
  const Dataset a = LoadDataset(dir / "a");
  WriteDataset(a, dir / "b");
  CopyImages(dir / "a", dir / "b");
  const Dataset b = LoadDataset(dir / "b");
  EXPECT_EQ(a.layout, b.layout);
  EXPECT_EQ(a.camera_angle_x, b.camera_angle_x);
  EXPECT_EQ(a.near, b.near);
  EXPECT_EQ(a.far, b.far);
  EXPECT_EQ(a.time_max_raw, b.time_max_raw);
  ExpectSameFrames(a.train, b.train, a.root, b.root);
  ExpectSameFrames(a.test, b.test, a.root, b.root);
  ExpectSameFrames(a.val, b.val, a.root, b.root);
  // Only the frame that differs carries intrinsics; the shared size is at the top.
  const json test = ReadJsonFile(dir / "b/transforms_test.json");
  EXPECT_EQ(test["w"], 8);
  EXPECT_EQ(test["h"], 6);
  EXPECT_EQ(test["frames"][0]["fl_x"], 7.5);
  EXPECT_FALSE(test["frames"][1].contains("fl_x"));
  EXPECT_FALSE(ReadJsonFile(dir / "b/transforms_train.json")["frames"][0].contains("exposures"));

  WriteDataset(a, dir / "c", {.write_val = false});
  EXPECT_FALSE(fs::exists(dir / "c/transforms_val.json"));
  EXPECT_TRUE(fs::exists(dir / "c/transforms_test.json"));
}

TEST(DatasetWriter, RoundTripLego) {
  const auto root = testing::SharedData("dnerf_lego_tiny");
  if (!root) GTEST_SKIP() << "shared data dnerf_lego_tiny is not available";
  TempDir dir;
  const Dataset a = LoadDataset(*root);
  WriteDataset(a, dir.path());
  fs::create_directory_symlink(*root / "images", dir / "images");
  const Dataset b = LoadDataset(dir.path());
  ExpectSameFrames(a.train, b.train, a.root, b.root);
  ExpectSameFrames(a.test, b.test, a.root, b.root);
  ExpectSameFrames(a.val, b.val, a.root, b.root);
  EXPECT_EQ(b.layout, "dnerf");
  // The shared intrinsics are the ones camera_angle_x implies: no fl_x is written.
  EXPECT_FALSE(ReadJsonFile(dir / "transforms_train.json").contains("fl_x"));
}

TEST(DatasetWriter, CommonIntrinsicsGoToTheTopLevel) {
  TempDir dir;
  Scene scene(dir / "a");
  AddGoodFrames(scene);
  for (const char* split : {"train", "test"}) {
    scene.File(split)["fl_x"] = 5.0;
    scene.File(split)["cx"] = 3.5;
  }
  scene.Write();
  const Dataset a = LoadDataset(dir / "a");
  WriteDataset(a, dir / "b");
  const json train = ReadJsonFile(dir / "b/transforms_train.json");
  EXPECT_EQ(train["fl_x"], 5.0);
  EXPECT_EQ(train["fl_y"], 5.0);
  EXPECT_EQ(train["cx"], 3.5);
  EXPECT_FALSE(train["frames"][0].contains("fl_x"));
  CopyImages(dir / "a", dir / "b");
  const Dataset b = LoadDataset(dir / "b");
  ExpectSameFrames(a.train, b.train, a.root, b.root);
}

TEST(DatasetWriter, FramesBuiltInMemory) {
  TempDir dir;
  Dataset d;
  d.camera_angle_x = kAngle;
  for (int i = 0; i < 2; ++i) {
    Frame f;
    f.split = i == 0 ? Split::kTrain : Split::kTest;
    f.image_path = dir / "images" / ("f" + std::to_string(i) + ".png");  // absolute: made relative
    f.hdr_path = dir / "hdr" / ("f" + std::to_string(i) + ".exr");
    f.time_raw = i;
    f.camera = {PinholeIntrinsics::FromFovX(kAngle, 8, 6), PoseOnRing(i)};
    (i == 0 ? d.train : d.test).push_back(f);
    WriteImage(f.image_path, RandomImage(8, 6, 3, i, 0, 1, Encoding::kSrgb));
    WriteImage(*f.hdr_path, RandomImage(8, 6, 3, i, 0, 1));
  }
  WriteDataset(d, dir.path());
  const Dataset back = LoadDataset(dir.path());
  EXPECT_EQ(back.train[0].file_path, "images/f0.png");
  EXPECT_EQ(*back.test[0].exr_file_path, "hdr/f1.exr");
  EXPECT_EQ(back.layout, "dnerf");

  // Invalid frames are refused with the file and frame named.
  d.test[0].camera.world_from_cam_gl(0, 0) = 2;
  try {
    WriteDataset(d, dir / "bad");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("transforms_test.json: frame 0: transform_matrix"),
              std::string::npos)
        << e.what();
  }
  d.test[0].camera.world_from_cam_gl = PoseOnRing(1);
  d.train[0].exposure_given = true;
  d.train[0].exposure = 0;
  EXPECT_THROW(WriteDataset(d, dir / "bad"), Error);
  d.train[0].exposure = 1;
  d.train[0].time_raw = std::nan("");
  EXPECT_THROW(WriteDataset(d, dir / "bad"), Error);
  d.train[0].time_raw = 0;
  d.train[0].image_path.clear();
  EXPECT_THROW(WriteDataset(d, dir / "bad"), Error);
}

// ---------------------------------------------------------------------------------------------
// The CLI: hdr4d dataset check.

TEST(DatasetCli, GoodSceneJson) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Write();
  const auto result = testing::RunHdr4d("dataset check '" + dir.path().string() + "' --json");
  ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
  const json out = json::parse(result.out);
  EXPECT_EQ(out["ok"], true);
  EXPECT_TRUE(out["problems"].empty());
  const json& s = out["summary"];
  EXPECT_EQ(s["layout"], "hdr4d");
  EXPECT_EQ(s["frames"]["train"], 3);
  EXPECT_EQ(s["frames"]["test"], 2);
  EXPECT_EQ(s["exposures"], json::array({0.5, 1.0, 1.5}));
  EXPECT_EQ(s["time_raw"]["max"], 2.0);
  EXPECT_EQ(s["time"]["max"], 1.0);
  EXPECT_EQ(s["hdr_gt"], "yes");
  EXPECT_EQ(s["resolution"]["width"], 8);
  EXPECT_TRUE(s["point_cloud"].is_null());
  EXPECT_EQ(out["profile"]["dynamic"], true);
  EXPECT_EQ(out["profile"]["multi_exposure"], true);
}

TEST(DatasetCli, BadSceneListsEveryProblemAndExitsOne) {
  TempDir dir;
  Scene scene(dir.path());
  AddGoodFrames(scene);
  scene.Frame("train", 1)["time"] = "abc";
  scene.Frame("test", 0)["exposures"] = -1;
  scene.Write();
  fs::remove(dir / "hdr/train_2.exr");
  const auto text = testing::RunHdr4d("dataset check '" + dir.path().string() + "'");
  EXPECT_EQ(text.exit_code, 1) << text.out << text.err;
  EXPECT_NE(text.out.find((dir / "transforms_train.json").string() +
                          ": frame 1: time: expected a number"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("transforms_train.json: frame 2: exr_file_path:"), std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("transforms_test.json: frame 0: exposures: must be positive"),
            std::string::npos)
      << text.out;
  // Small exposures with a negative one also look like log2 stops: said as a fourth problem.
  EXPECT_NE(text.out.find("transforms_test.json: exposures: all 5 exposures are small"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("4 problems found"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("layout:"), std::string::npos) << text.out;  // summary still printed

  const auto js = testing::RunHdr4d("dataset check '" + dir.path().string() + "' --json --full");
  EXPECT_EQ(js.exit_code, 1);
  const json out = json::parse(js.out);
  EXPECT_EQ(out["ok"], false);
  ASSERT_EQ(out["problems"].size(), 4u);
  EXPECT_EQ(out["problems"][0]["frame"], 1);
  EXPECT_EQ(out["problems"][0]["key"], "time");
  EXPECT_FALSE(out["summary"].is_null());

  fs::remove(dir / "transforms_train.json");
  const auto missing = testing::RunHdr4d("dataset check '" + dir.path().string() + "' --json");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_TRUE(json::parse(missing.out)["summary"].is_null());
}

TEST(DatasetCli, LegoSummary) {
  const auto root = testing::SharedData("dnerf_lego_tiny");
  if (!root) GTEST_SKIP() << "shared data dnerf_lego_tiny is not available";
  const auto result = testing::RunHdr4d("dataset check '" + root->string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
  EXPECT_NE(result.out.find("layout:      dnerf"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("50 train, 20 test, 11 val"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("resolution:  100x100"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("HDR GT:      no"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("dynamic:"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("monocular:"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("ok: no problems"), std::string::npos) << result.out;

  const auto reference =
      testing::RunHdr4d("dataset check '" + root->string() + "' --json --reference-time");
  ASSERT_EQ(reference.exit_code, 0);
  const json s = json::parse(reference.out)["summary"];
  EXPECT_EQ(s["frames"]["val"], 11);
  EXPECT_EQ(s["hdr_gt"], "no");
  EXPECT_EQ(s["exposures"], json::array({1.0}));
}

TEST(DatasetCli, HelpAndMissingSubcommand) {
  const auto bare = testing::RunHdr4d("dataset");
  EXPECT_NE(bare.exit_code, 0);
  EXPECT_NE(bare.err.find("check"), std::string::npos) << bare.err;
  EXPECT_NE(bare.err.find("subcommand is required"), std::string::npos) << bare.err;
  const auto help = testing::RunHdr4d("dataset check --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--reference-time"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--full"), std::string::npos) << help.out;
}

}  // namespace
}  // namespace hdr4d

// ---- nerfstudio's single transforms.json ----------------------------------------------------

namespace hdr4d {
namespace {

// n frames with PNGs, intrinsics at the top level, no time keys.
json NerfstudioDoc(const fs::path& root, int n) {
  json doc = {{"fl_x", 10.0},
              {"fl_y", 11.0},
              {"cx", 4.0},
              {"cy", 3.0},
              {"w", 8},
              {"h", 6},
              {"camera_model", "OPENCV"},
              {"k1", 0.0},
              {"k2", 0.0},
              {"p1", 0.0},
              {"p2", 0.0},
              {"frames", json::array()}};
  for (int i = 0; i < n; ++i) {
    const std::string name = "images/frame_" + std::to_string(i) + ".png";
    WriteImage(root / name, RandomImage(8, 6, 3, 100 + i, 0, 1, Encoding::kSrgb));
    doc["frames"].push_back({{"file_path", name}, {"transform_matrix", Rows(PoseOnRing(i))}});
  }
  return doc;
}

TEST(Nerfstudio, EveryEighthFrameIsHeldOutForTest) {
  TempDir dir;
  WriteJsonFile(dir / "transforms.json", NerfstudioDoc(dir.path(), 17));
  const Dataset d = LoadDataset(dir.path());
  EXPECT_EQ(d.layout, "nerfstudio");
  ASSERT_EQ(d.test.size(), 3u);  // frames 0, 8, 16
  EXPECT_EQ(d.test[1].index, 8);
  EXPECT_EQ(d.train.size(), 14u);
  EXPECT_DOUBLE_EQ(d.train[0].camera.intrinsics.fy, 11.0);
  EXPECT_DOUBLE_EQ(d.train[0].camera.intrinsics.cx, 4.0);
  EXPECT_DOUBLE_EQ(d.train[0].time, 0.0);  // no time key: a static capture
}

TEST(Nerfstudio, ExplicitSplitListsAndPlyFilePath) {
  TempDir dir;
  json doc = NerfstudioDoc(dir.path(), 5);
  doc["test_filenames"] = {"images/frame_3.png"};
  doc["val_filenames"] = {"images/frame_4.png"};
  PointCloud cloud;
  cloud.positions = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 2, 3)};
  WritePly(dir / "sparse_pc.ply", cloud);
  doc["ply_file_path"] = "sparse_pc.ply";
  WriteJsonFile(dir / "transforms.json", doc);
  const DatasetReport report = CheckDataset(dir.path());
  ASSERT_TRUE(report.problems.empty()) << AllProblems(report);
  const Dataset& d = *report.dataset;
  ASSERT_EQ(d.test.size(), 1u);
  EXPECT_EQ(d.test[0].index, 3);
  ASSERT_EQ(d.val.size(), 1u);
  EXPECT_EQ(d.train.size(), 3u);
  ASSERT_TRUE(d.point_cloud_path.has_value());
  EXPECT_EQ(d.point_cloud_path->filename(), "sparse_pc.ply");
  EXPECT_EQ(report.point_cloud_points, 2);
}

TEST(Nerfstudio, DistortionAndMissingPlyAreProblems) {
  TempDir dir;
  json doc = NerfstudioDoc(dir.path(), 3);
  doc["k1"] = 0.1;
  doc["ply_file_path"] = "nope.ply";
  WriteJsonFile(dir / "transforms.json", doc);
  const DatasetReport report = CheckDataset(dir.path());
  ASSERT_EQ(report.problems.size(), 2u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms.json", -1, "k1", "distortion");
  EXPECT_PROBLEM(report, "transforms.json", -1, "ply_file_path", "not found");
  doc["k1"] = 0.0;
  doc["camera_model"] = "OPENCV_FISHEYE";
  doc.erase("ply_file_path");
  WriteJsonFile(dir / "transforms.json", doc);
  const DatasetReport fisheye = CheckDataset(dir.path());
  ASSERT_EQ(fisheye.problems.size(), 1u) << AllProblems(fisheye);
  EXPECT_PROBLEM(fisheye, "transforms.json", -1, "camera_model", "not supported");
}

// The sweep of session 94: split lists naming no frame (every test view then trained on), a
// file in two lists, a frame's own distortion, and one frame without the time the others give
// were all read without a word.
TEST(Nerfstudio, SplitListsDistortionPerFrameAndAMissingTimeAreProblems) {
  TempDir dir;
  json doc = NerfstudioDoc(dir.path(), 4);
  doc["test_filenames"] = {"imgs/frame_3.png", "images/frame_2.png"};
  doc["train_filenames"] = {"images/frame_0.png", "images/frame_1.png", "images/frame_2.png"};
  doc["frames"][1]["k1"] = 0.2;
  for (int i = 0; i < 4; ++i) doc["frames"][i]["time"] = i;
  doc["frames"][3].erase("time");
  WriteJsonFile(dir / "transforms.json", doc);
  const DatasetReport report = CheckDataset(dir.path());
  EXPECT_EQ(report.problems.size(), 4u) << AllProblems(report);
  EXPECT_PROBLEM(report, "transforms.json", -1, "test_filenames",
                 "'imgs/frame_3.png' is no frame's file_path");
  EXPECT_PROBLEM(report, "transforms.json", -1, "train_filenames",
                 "'images/frame_2.png' is listed in test_filenames too");
  EXPECT_PROBLEM(report, "transforms.json", 1, "k1", "distortion");
  EXPECT_PROBLEM(report, "transforms.json", 3, "time",
                 "missing, while 3 of the scene's 4 frames give one (it would be read as time 0)");
}

}  // namespace
}  // namespace hdr4d
