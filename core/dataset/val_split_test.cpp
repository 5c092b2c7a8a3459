// `hdr4d dataset split-val`: which frames move, that nothing else changes, and the refusals.
#include "core/dataset/val_split.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/dataset/demo_scene.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using testing::ErrorOf;
using testing::TempDir;

// The demo scene at 16 px: six times, three cameras (the third held out for test), three
// exposures: 2 x 6 x 3 = 36 training frames.
void MakeScene(const fs::path& root, int cameras = 3) {
  DemoSceneOptions s;
  s.width = s.height = 16;
  s.num_timestamps = 6;
  s.num_cameras = cameras;
  s.samples_per_axis = 1;
  MakeDemoScene(s, root);
}

TEST(ValSplit, EveryKthTimeMovesEveryFrameOfTheMiddleTimeOfEachRunOfK) {
  TempDir dir;
  MakeScene(dir / "scene");
  const std::string train_before = testing::ReadTextFile(dir / "scene" / "transforms_train.json");
  const ValSplitSummary s = SplitOffVal(dir / "scene", dir / "split", {.every_time = 3});
  EXPECT_EQ(s.moved, 12u);  // times 1 and 4 (of 0..5), two cameras, three exposures
  EXPECT_EQ(s.kept, 24u);
  // The original is untouched; the new scene reads, with the val split.
  EXPECT_EQ(testing::ReadTextFile(dir / "scene" / "transforms_train.json"), train_before);
  EXPECT_FALSE(fs::exists(dir / "scene" / "transforms_val.json"));
  const Dataset before = LoadDataset(dir / "scene", {.image_check = ImageCheck::kNone});
  const Dataset after = LoadDataset(dir / "split", {.image_check = ImageCheck::kNone});
  ASSERT_EQ(after.val.size(), 12u);
  EXPECT_EQ(after.train.size(), 24u);
  EXPECT_EQ(after.test.size(), before.test.size());
  std::set<double> times, val_times;
  for (const Frame& f : before.train) times.insert(f.time_raw);
  for (const Frame& f : after.val) val_times.insert(f.time_raw);
  const std::vector<double> sorted(times.begin(), times.end());
  EXPECT_EQ(val_times, (std::set<double>{sorted[1], sorted[4]}));
  for (const Frame& f : after.train) EXPECT_EQ(val_times.count(f.time_raw), 0u) << f.file_path;
  // Each frame keeps every key, and the files their top level; the test file is a copy.
  const nlohmann::json original = ReadJsonFile(dir / "scene" / "transforms_train.json");
  const nlohmann::json val = ReadJsonFile(dir / "split" / "transforms_val.json");
  EXPECT_EQ(val["frames"][0], original["frames"][3]);  // camera 0, time 1, exposure 0
  nlohmann::json top = original, val_top = val;
  top.erase("frames");
  val_top.erase("frames");
  EXPECT_EQ(val_top, top);
  EXPECT_EQ(testing::ReadTextFile(dir / "split" / "transforms_test.json"),
            testing::ReadTextFile(dir / "scene" / "transforms_test.json"));
  // The images are the original's, through links.
  EXPECT_TRUE(fs::is_symlink(dir / "split" / "hdr"));
  EXPECT_TRUE(fs::exists(after.val[0].hdr_path.value()));
}

TEST(ValSplit, ACameraOfARigMovesAllItsFrames) {
  TempDir dir;
  MakeScene(dir / "scene", 4);
  const ValSplitSummary s = SplitOffVal(dir / "scene", dir / "split", {.camera_id = 1});
  EXPECT_EQ(s.moved, 18u);  // six times x three exposures
  EXPECT_EQ(s.kept, 36u);
  const Dataset after = LoadDataset(dir / "split", {.image_check = ImageCheck::kNone});
  for (const Frame& f : after.val) EXPECT_EQ(f.camera_id, 1);
  for (const Frame& f : after.train) EXPECT_NE(f.camera_id, 1);
  EXPECT_NE(s.what.find("camera 1"), std::string::npos);
}

TEST(ValSplit, RefusalsNameTheFileAndWriteNothing) {
  TempDir dir;
  MakeScene(dir / "scene");
  const fs::path scene = dir / "scene";
  auto refused = [&](const ValSplitOptions& o, const std::string& part, const fs::path& from) {
    const std::string message = ErrorOf([&] { SplitOffVal(from, dir / "out", o); });
    EXPECT_NE(message.find(part), std::string::npos) << message;
    EXPECT_FALSE(fs::exists(dir / "out")) << message;
  };
  refused({}, "one of --every-time K, --every-frame K and --camera ID", scene);
  refused({.every_time = 2, .camera_id = 0}, "one of --every-time K, --every-frame K", scene);
  refused({.camera_id = 0, .every_frame = 2}, "one of --every-time K, --every-frame K", scene);
  refused({.every_time = 1}, "K >= 2", scene);
  refused({.every_frame = 1}, "--every-frame 1 would move every training frame", scene);
  refused({.every_frame = 80}, "--every-frame 80 chooses none of the 36 training frames", scene);
  refused({.every_time = 20}, "chooses none of the 6 training times", scene);
  refused({.camera_id = 7}, "no training frame has camera_id 7 (the training cameras: 0, 1)",
          scene);
  refused({.every_time = 2}, "transforms_train.json and transforms_test.json", dir / "nowhere");
  // A rig with one training camera: holding it back leaves nothing.
  MakeScene(dir / "two", 2);
  refused({.camera_id = 0}, "nothing would be left to train on", dir / "two");
  // A scene with a val split already.
  fs::copy_file(scene / "transforms_test.json", scene / "transforms_val.json");
  refused({.every_time = 2}, "already has a val split", scene);
  fs::remove(scene / "transforms_val.json");
  // An output folder that is there and not empty is not merged into.
  fs::create_directories(dir / "busy");
  testing::WriteTextFile(dir / "busy" / "keep.txt", "mine");
  const std::string message = ErrorOf([&] { SplitOffVal(scene, dir / "busy", {.every_time = 2}); });
  EXPECT_NE(message.find((dir / "busy").string()), std::string::npos) << message;
  EXPECT_EQ(testing::ReadTextFile(dir / "busy" / "keep.txt"), "mine");
}

// A static capture of separate views: one in K, the middle of each run of K in file order.
TEST(ValSplit, EveryKthFrameMovesTheMiddleFrameOfEachRunOfK) {
  TempDir dir;
  MakeScene(dir / "scene");
  const ValSplitSummary s = SplitOffVal(dir / "scene", dir / "split", {.every_frame = 3});
  EXPECT_EQ(s.moved, 12u);
  EXPECT_EQ(s.kept, 24u);
  const nlohmann::json original = ReadJsonFile(dir / "scene" / "transforms_train.json");
  const nlohmann::json val = ReadJsonFile(dir / "split" / "transforms_val.json");
  ASSERT_EQ(val["frames"].size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(val["frames"][i], original["frames"][1 + 3 * i]);
}

// nerfstudio's one transforms.json: n frames on a line, no time, no split lists.
nlohmann::json NerfstudioDoc(int n) {
  nlohmann::json doc = {{"fl_x", 10.0},
                        {"fl_y", 10.0},
                        {"cx", 4.0},
                        {"cy", 3.0},
                        {"w", 8},
                        {"h", 6},
                        {"camera_model", "PINHOLE"},
                        {"frames", nlohmann::json::array()}};
  for (int i = 0; i < n; ++i) {
    const nlohmann::json pose = {{1, 0, 0, 0.1 * i}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    doc["frames"].push_back(
        {{"file_path", "images/frame_" + std::to_string(i) + ".png"}, {"transform_matrix", pose}});
  }
  return doc;
}

std::set<int> Indices(const std::vector<Frame>& frames) {
  std::set<int> out;
  for (const Frame& f : frames) out.insert(f.index);
  return out;
}

TEST(ValSplit, ANerfstudioSceneGetsValFilenamesAndKeepsItsTestSplit) {
  TempDir dir;
  fs::create_directories(dir / "scene" / "images");
  WriteJsonFile(dir / "scene" / "transforms.json", NerfstudioDoc(17));
  const std::string before = testing::ReadTextFile(dir / "scene" / "transforms.json");
  // No lists: frames 0, 8 and 16 are the test split; training frames 1-7 and 9-15, of which
  // the middle of each run of four (file order) moves: 3, 7 and 12.
  const ValSplitSummary s = SplitOffVal(dir / "scene", dir / "split", {.every_frame = 4});
  EXPECT_EQ(s.moved, 3u);
  EXPECT_EQ(s.kept, 11u);
  EXPECT_EQ(testing::ReadTextFile(dir / "scene" / "transforms.json"), before);
  const Dataset after = LoadDataset(dir / "split", {.image_check = ImageCheck::kNone});
  EXPECT_EQ(after.layout, "nerfstudio");
  EXPECT_EQ(Indices(after.test), (std::set<int>{0, 8, 16}));
  EXPECT_EQ(Indices(after.val), (std::set<int>{3, 7, 12}));
  EXPECT_EQ(after.train.size(), 11u);
  // The file is the original but for the two lists; the images are linked.
  nlohmann::json doc = ReadJsonFile(dir / "split" / "transforms.json");
  EXPECT_EQ(doc["val_filenames"],
            nlohmann::json({"images/frame_3.png", "images/frame_7.png", "images/frame_12.png"}));
  EXPECT_EQ(doc["test_filenames"],
            nlohmann::json({"images/frame_0.png", "images/frame_8.png", "images/frame_16.png"}));
  doc.erase("val_filenames");
  doc.erase("test_filenames");
  EXPECT_EQ(doc, ReadJsonFile(dir / "scene" / "transforms.json"));
  EXPECT_TRUE(fs::is_symlink(dir / "split" / "images"));
  EXPECT_FALSE(fs::exists(dir / "split" / "transforms_train.json"));

  // Given lists are kept; the moved frames leave train_filenames.
  nlohmann::json listed = NerfstudioDoc(6);
  listed["train_filenames"] = {"images/frame_0.png", "images/frame_1.png", "images/frame_2.png",
                               "images/frame_3.png", "images/frame_4.png"};
  listed["test_filenames"] = {"images/frame_5.png"};
  fs::create_directories(dir / "listed" / "images");
  WriteJsonFile(dir / "listed" / "transforms.json", listed);
  SplitOffVal(dir / "listed", dir / "listed_split", {.every_frame = 2});
  const nlohmann::json out = ReadJsonFile(dir / "listed_split" / "transforms.json");
  EXPECT_EQ(out["train_filenames"],
            nlohmann::json({"images/frame_0.png", "images/frame_2.png", "images/frame_4.png"}));
  EXPECT_EQ(out["val_filenames"], nlohmann::json({"images/frame_1.png", "images/frame_3.png"}));
  EXPECT_EQ(out["test_filenames"], listed["test_filenames"]);
  const Dataset listed_after =
      LoadDataset(dir / "listed_split", {.image_check = ImageCheck::kNone});
  EXPECT_EQ(Indices(listed_after.train), (std::set<int>{0, 2, 4}));
  EXPECT_EQ(Indices(listed_after.val), (std::set<int>{1, 3}));
}

TEST(ValSplit, NerfstudioRefusalsNameTransformsJson) {
  TempDir dir;
  fs::create_directories(dir / "scene" / "images");
  const fs::path file = dir / "scene" / "transforms.json";
  WriteJsonFile(file, NerfstudioDoc(9));
  auto refused = [&](const ValSplitOptions& o, const std::string& part) {
    const std::string message = ErrorOf([&] { SplitOffVal(dir / "scene", dir / "out", o); });
    EXPECT_NE(message.find(part), std::string::npos) << message;
    EXPECT_FALSE(fs::exists(dir / "out")) << message;
  };
  refused({.every_time = 2}, file.string() + ": every training frame has the same time");
  refused({.camera_id = 0}, "none given; --every-frame K holds back views");
  refused({.every_frame = 20}, file.string() + ": --every-frame 20 chooses none of the 7");
  // datagen's in-place split writes the reference layout only.
  const std::string in_place =
      ErrorOf([&] { SplitValInPlace(dir / "scene", {.every_frame = 2}, "datagen"); });
  EXPECT_NE(in_place.find("transforms_train.json and transforms_test.json"), std::string::npos)
      << in_place;
  nlohmann::json with_val = NerfstudioDoc(9);
  with_val["val_filenames"] = {"images/frame_1.png"};
  WriteJsonFile(file, with_val);
  refused({.every_frame = 2}, file.string() + ": the scene already has a val split (1 frames)");
}

// In place (datagen --val-every, in its staging folder): the same frames move, no links, and
// the refusals name the caller's flag.
TEST(ValSplit, InPlaceMovesTheSameFramesAndNamesTheFlag) {
  const InputProtectionScope scope;  // as in a command: the scene's files are its inputs
  TempDir dir;
  MakeScene(dir / "scene");
  MakeScene(dir / "copy");
  const ValSplitSummary linked = SplitOffVal(dir / "copy", dir / "split", {.every_time = 3});
  const ValSplitSummary s = SplitValInPlace(dir / "scene", {.every_time = 3}, "datagen");
  EXPECT_EQ(s.moved, linked.moved);
  EXPECT_EQ(s.kept, linked.kept);
  EXPECT_EQ(testing::ReadTextFile(dir / "scene" / "transforms_val.json"),
            testing::ReadTextFile(dir / "split" / "transforms_val.json"));
  EXPECT_EQ(testing::ReadTextFile(dir / "scene" / "transforms_train.json"),
            testing::ReadTextFile(dir / "split" / "transforms_train.json"));
  EXPECT_FALSE(fs::is_symlink(dir / "scene" / "hdr"));
  const std::string again =
      ErrorOf([&] { SplitValInPlace(dir / "scene", {.every_time = 3}, "datagen"); });
  EXPECT_NE(again.find("already has a val split"), std::string::npos) << again;
  const std::string none = ErrorOf([&] {
    SplitValInPlace(dir / "copy", {.every_time = 40, .every_time_flag = "--val-every"}, "datagen");
  });
  EXPECT_NE(none.find("--val-every 40 chooses none"), std::string::npos) << none;
  EXPECT_FALSE(fs::exists(dir / "copy" / "transforms_val.json"));
}

TEST(ValSplitCli, WritesTheSceneAndSaysWhatMoved) {
  TempDir dir;
  MakeScene(dir / "scene");
  const std::string scene = "'" + (dir / "scene").string() + "'";
  const auto ok = testing::RunHdr4d("dataset split-val " + scene + " --out '" +
                                    (dir / "split").string() + "' --every-time 3");
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("12 training frames moved to val"), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("24 left to train on"), std::string::npos) << ok.out;
  const auto both = testing::RunHdr4d("dataset split-val " + scene + " --out '" +
                                      (dir / "both").string() + "' --every-time 3 --camera 0");
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("excludes"), std::string::npos) << both.err;
  EXPECT_FALSE(fs::exists(dir / "both"));
  const auto frame_and_camera =
      testing::RunHdr4d("dataset split-val " + scene + " --out '" + (dir / "both").string() +
                        "' --every-frame 3 --camera 0");
  EXPECT_NE(frame_and_camera.exit_code, 0);
  EXPECT_NE(frame_and_camera.err.find("excludes"), std::string::npos) << frame_and_camera.err;
  EXPECT_FALSE(fs::exists(dir / "both"));
  const auto help = testing::RunHdr4d("dataset split-val --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--every-time"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--every-frame"), std::string::npos) << help.out;
}

}  // namespace
}  // namespace hdr4d
