// The driver with a stand-in for Blender: a shell script that copies prepared files (renders,
// points, render_info.json) next to the plan, or fails the way Blender can. These run without
// Blender; blender_scenes_test.cpp runs the real one.
#include "datagen/generator.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "core/geometry/camera.h"
#include "core/dataset/dataset.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/radiometry/ldr_synthesis.h"
#include "core/geometry/ply.h"
#include "datagen/capture_generator.h"
#include "datagen/scene_presets.h"
#include "core/files/sha256.h"
#include "tests/testing.h"

namespace hdr4d::datagen {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ErrorOf;
using testing::TempDir;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A fake `blender`: finds the plan (the last argument), copies FIXTURE's files next to it, prints
// `body`'s output and exits with its status.
fs::path WriteFakeBlender(const fs::path& dir, const fs::path& fixture, const std::string& body) {
  const fs::path path = dir / "fake-blender";
  testing::WriteTextFile(
      path, "#!/bin/sh\nfor a in \"$@\"; do plan=\"$a\"; done\nout=$(dirname \"$plan\")\n" +
                (fixture.empty() ? "" : "cp -r '" + fixture.string() + "'/. \"$out\"/\n") + body);
  chmod(path.c_str(), 0755);
  return path;
}

// What a successful Blender run leaves next to the plan for the ci airplane: small bright EXRs,
// 50 surface points (x y z r g b t, 25 at t = 0.25 and 25 at t = 0.75, or `point_time` for all)
// and render_info.json with cameras on a ring looking at the origin.
void WriteFixture(const fs::path& fixture,
                  const ScenePreset& preset,
                  bool write_exrs = true,
                  bool corrupt_exrs = false,
                  std::optional<float> point_time = std::nullopt) {
  json renders = json::array();
  int i = 0;
  for (const PlannedRender& r : PlanRenders(preset)) {
    const double angle = 0.3 * i++;
    const Eigen::Matrix4d pose = LookAtWorldFromCamGl(
        {4 * std::cos(angle), 4 * std::sin(angle), 1.5}, {0, 0, 0.5}, Eigen::Vector3d::UnitZ());
    json m = json::array();
    for (int row = 0; row < 4; ++row)
      m.push_back({pose(row, 0), pose(row, 1), pose(row, 2), pose(row, 3)});
    renders.push_back({{"file", r.hdr_file},
                       {"camera_id", r.camera_id},
                       {"time_index", r.time_index},
                       {"time", r.time},
                       {"transform_matrix", m},
                       {"markers", json::array()}});
    if (corrupt_exrs) {
      testing::WriteTextFile(fixture / r.hdr_file, "not an exr");
    } else if (write_exrs) {
      Image hdr = testing::RandomImage(preset.width, preset.height, 3, 17 + i, 0.001f, 1.0f);
      hdr.at(3, 3, 0) = 500.0f;  // an emitter
      WriteImage(fixture / r.hdr_file, hdr, {.format = PixelFormat::kFloat});
    }
  }
  WriteJsonFile(fixture / "render_info.json", {{"blender_version", "3.4.1"},
                                               {"script_version", 2},
                                               {"camera_angle_x", preset.camera_angle_x},
                                               {"points", {{"count", 50}, {"times", {0.25, 0.75}}}},
                                               {"renders", renders}});
  std::vector<float> points;
  for (int p = 0; p < 50; ++p) {
    const float t = point_time.value_or(p < 25 ? 0.25f : 0.75f);
    points.insert(points.end(), {0.01f * p, -0.02f * p, 0.5f, 0.2f, 0.4f, 0.6f, t});
  }
  std::ofstream(fixture / "points_t0.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(points.data()), points.size() * sizeof(float));
}

struct Fixture {
  TempDir dir;
  DatagenOptions options;
  ScenePreset preset = ResolvePreset("airplane", "ci");
  Fixture() {
    options.scene = "airplane";
    options.preset = "ci";
    options.out = dir / "out";
    options.show_progress = false;
    options.seed = 3;
  }
};

TEST(Generator, WritesACompleteCheckedDatasetAroundTheRenders) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture",
                                       "echo HDR4D_RENDERED 1 6 hdr/cam00_t0000.exr\n")
                          .string();
  const SceneResult result = GenerateScene(f.options, "airplane");
  const fs::path root = f.options.out / "airplane";
  EXPECT_EQ(result.root, root);
  EXPECT_EQ(result.renders, 6);
  EXPECT_EQ(result.ldr_images, 6);
  EXPECT_FALSE(fs::exists(f.options.out / "airplane.partial"));
  EXPECT_FALSE(fs::exists(root / "points_t0.bin"));
  EXPECT_GT(result.range.max, 100.0);

  const Dataset dataset = LoadDataset(root, {.image_check = ImageCheck::kFull});
  ASSERT_EQ(dataset.train.size(), 5u);
  ASSERT_EQ(dataset.test.size(), 1u);
  const Frame& test = dataset.test[0];
  EXPECT_DOUBLE_EQ(test.time, 0.6);  // timestamp 3 of 0..5
  EXPECT_EQ(test.exposure, 0.125);   // exposures cycle over time: 3 mod 3 = 0
  EXPECT_EQ(test.camera_id, 0);
  EXPECT_EQ(test.exposure_index, 0);
  EXPECT_EQ(*test.exr_file_path, "hdr/cam00_t0003.exr");
  EXPECT_EQ(test.file_path, "images/cam00_t0003_e0.png");
  EXPECT_NEAR(dataset.camera_angle_x, kSynCameraAngleX, 1e-12);
  EXPECT_EQ(dataset.train[1].exposure, 2.0);
  EXPECT_EQ(dataset.train[2].exposure, 32.0);

  const PointCloud cloud = ReadPly(root / "point3d.ply");
  ASSERT_EQ(cloud.size(), 50u);
  ASSERT_TRUE(cloud.has_times());
  for (int p = 0; p < 50; ++p) EXPECT_EQ(cloud.times[p], p < 25 ? 0.25f : 0.75f) << p;
  EXPECT_NEAR(cloud.positions[10].x(), 0.1f, 1e-6);
  EXPECT_NEAR(cloud.colors[40].z(), 0.6f, 0.5f / 255);

  const json manifest = ReadJsonFile(root / "manifest.json");
  EXPECT_EQ(manifest["generator"], "hdr4d datagen");
  EXPECT_EQ(manifest["scene"], "airplane");
  EXPECT_EQ(manifest["preset"], "ci");
  EXPECT_EQ(manifest["seed"], 3);
  EXPECT_EQ(manifest["points"]["count"], 50);
  EXPECT_EQ(manifest["points"]["times"], json({0.25, 0.75}));
  EXPECT_EQ(manifest["blender_version"], "3.4.1");
  EXPECT_EQ(manifest["counts"]["train"]["ldr"], 5);
  EXPECT_EQ(manifest["ldr_synthesis"]["crf_spec"], "filmic:1.5,0.18");
  EXPECT_GT(manifest["dynamic_range"]["ratio_p99.9_p0.1"].get<double>(), 10.0);
  // Every file but the manifest and the log is listed, with its real checksum.
  const json& files = manifest["files"];
  EXPECT_EQ(files.size(), 6u /*hdr*/ + 6u /*png*/ + 5u /*json*/ + 1u /*ply*/);
  for (const auto& [name, sha] : files.items()) EXPECT_EQ(Sha256File(root / name), sha) << name;
  EXPECT_TRUE(files.contains("hdr/cam00_t0000.exr"));
  EXPECT_TRUE(files.contains("transforms_test.json"));
  EXPECT_FALSE(files.contains("blender.log"));
  EXPECT_TRUE(Contains(testing::ReadTextFile(root / "blender.log"), "HDR4D_RENDERED 1 6"));
}

// --reuse-renders: another camera pipeline of a scene from the renders of an earlier dataset,
// without Blender; the same LDR options give the same files; another plan renders.
TEST(Generator, ReuseRendersTakesAnEarlierDatasetsRendersAndMakesItsOwnLdr) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  GenerateScene(f.options, "airplane");
  const fs::path first = f.options.out / "airplane";
  const json first_files = ReadJsonFile(first / "manifest.json")["files"];

  DatagenOptions phone = f.options;
  phone.out = f.dir / "phone";
  phone.reuse_renders = f.options.out;
  phone.pipeline.name = "phone";
  phone.blender = WriteFakeBlender(f.dir / "phone", "", "echo 'Blender ran' >&2\nexit 1\n").string();
  const SceneResult reused = GenerateScene(phone, "airplane");
  EXPECT_EQ(reused.renders_reused_from, first);
  const fs::path root = phone.out / "airplane";
  LoadDataset(root, {.image_check = ImageCheck::kFull});
  const json manifest = ReadJsonFile(root / "manifest.json");
  EXPECT_EQ(manifest["renders_reused_from"], first.string());
  int ldr_differs = 0;
  for (const auto& [name, sha] : manifest["files"].items()) {
    if (name.rfind("hdr/", 0) == 0 || name == "point3d.ply" || name == "render_info.json")
      EXPECT_EQ(sha, first_files[name]) << name;  // the renders, as they were
    if (name.rfind("images/", 0) == 0) ldr_differs += sha != first_files[name];
  }
  EXPECT_EQ(ldr_differs, 6);  // every LDR image through the phone pipeline
  EXPECT_TRUE(Contains(testing::ReadTextFile(root / "blender.log"), "reused"));

  // The first dataset's own options from its renders: the same files, byte for byte.
  DatagenOptions again = f.options;
  again.out = f.dir / "again";
  again.reuse_renders = f.options.out;
  again.blender = phone.blender;
  GenerateScene(again, "airplane");
  EXPECT_EQ(ReadJsonFile(again.out / "airplane" / "manifest.json")["files"], first_files);

  // Another plan (another width), or no dataset there: Blender renders (and fails here).
  for (const fs::path& source : {f.options.out, f.dir / "nothing"}) {
    DatagenOptions other = phone;
    other.out = f.dir / "other";
    other.reuse_renders = source;
    if (source == f.options.out) other.width = 40;
    EXPECT_TRUE(Contains(ErrorOf([&] { GenerateScene(other, "airplane"); }), "Blender ran"))
        << source;
  }
  DatagenOptions capture = phone;
  capture.capture = true;
  capture.pipeline = {};
  EXPECT_TRUE(Contains(ErrorOf([&] { capture.Validate(); }), "--reuse-renders"));
}

// --val-every K: one training time in K moves to transforms_val.json after the LDR synthesis, so
// the images are the same as without it; the manifest says what moved; a K that chooses nothing
// fails before the scene is moved into place.
TEST(Generator, ValEveryMovesOneTrainingTimeInKToAValSplit) {
  Fixture f;
  // One command's input protection around each run, as the CLI does: the datasets read are
  // inputs, and the split rewrites two of their files.
  auto generate = [](const DatagenOptions& o) {
    const InputProtectionScope scope;
    return GenerateScene(o, "airplane");
  };
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  generate(f.options);
  const json plain = ReadJsonFile(f.options.out / "airplane" / "manifest.json")["files"];

  DatagenOptions split = f.options;
  split.out = f.dir / "split";
  split.val_every = 2;
  const SceneResult result = generate(split);
  const fs::path root = split.out / "airplane";
  const Dataset dataset = LoadDataset(root, {.image_check = ImageCheck::kFull});
  // The ci airplane trains on timestamps 0, 1, 2, 4, 5 (3 is the test's): the 2nd and 4th go.
  ASSERT_EQ(dataset.val.size(), 2u);
  EXPECT_EQ(dataset.train.size(), 3u);
  EXPECT_EQ(dataset.test.size(), 1u);
  EXPECT_EQ(dataset.val[0].file_path, "images/cam00_t0001_e1.png");
  EXPECT_EQ(dataset.val[1].file_path, "images/cam00_t0004_e1.png");
  EXPECT_EQ(result.val_frames, 2);
  const json manifest = ReadJsonFile(root / "manifest.json");
  EXPECT_EQ(manifest["val_split"]["val_every"], 2);
  EXPECT_EQ(manifest["val_split"]["frames"], 2);
  EXPECT_TRUE(manifest["files"].contains("transforms_val.json"));
  for (const auto& [name, sha] : plain.items()) {  // the images and renders are the same bytes
    if (name.rfind("images/", 0) == 0 || name.rfind("hdr/", 0) == 0) {
      EXPECT_EQ(manifest["files"][name], sha) << name;
    }
  }

  // Too few training times for K: an error naming the flag; the earlier scene stays.
  split.val_every = 20;
  const std::string message = ErrorOf([&] { generate(split); });
  EXPECT_TRUE(Contains(message, "--val-every 20 chooses none of the 5 training times")) << message;
  EXPECT_EQ(LoadDataset(root, {.image_check = ImageCheck::kNone}).val.size(), 2u);

  DatagenOptions bad = f.options;
  bad.val_every = 1;
  EXPECT_TRUE(Contains(ErrorOf([&] { bad.Validate(); }), "--val-every 1: give K >= 2"));
  bad.val_every = -3;
  EXPECT_TRUE(Contains(ErrorOf([&] { bad.Validate(); }), "--val-every -3"));
  bad.val_every = 8;
  bad.capture = true;
  bad.scene = "room";
  EXPECT_TRUE(Contains(ErrorOf([&] { bad.Validate(); }), "a capture has none"));
  bad.val_every.reset();  // unset: a capture gets none, and no refusal
  EXPECT_EQ(ErrorOf([&] { bad.Validate(); }), "");
}

// Unset, one moving camera with 16 or more training times gets one in 8 (the mini and paper
// presets of the four monocular scenes); rigs and the ci preset get none; a given K wins.
TEST(Generator, ValEveryDefaultsToEightForOneMovingCameraOnly) {
  DatagenOptions o;
  for (const char* scene : {"airplane", "deer", "lego", "tank"}) {
    EXPECT_EQ(o.ValEveryFor(ResolvePreset(scene, "mini")), kMonocularValEvery) << scene;
    EXPECT_EQ(o.ValEveryFor(ResolvePreset(scene, "paper")), kMonocularValEvery) << scene;
    EXPECT_EQ(o.ValEveryFor(ResolvePreset(scene, "ci")), 0) << scene;
  }
  for (const char* scene : {"hook", "jump", "mutant", "standup", "studio", "marker"})
    EXPECT_EQ(o.ValEveryFor(ResolvePreset(scene, "mini")), 0) << scene;
  o.val_every = 0;
  EXPECT_EQ(o.ValEveryFor(ResolvePreset("lego", "mini")), 0);
  o.val_every = 4;
  EXPECT_EQ(o.ValEveryFor(ResolvePreset("hook", "mini")), 4);
}

TEST(Generator, RerunReplacesItsOwnPreviousOutput) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  std::vector<std::string> done;
  const auto results = Generate(f.options, [&](const SceneResult& r) { done.push_back(r.scene); });
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(done, std::vector<std::string>{"airplane"});
  // A file of the previous run that this one does not write goes too (the val split).
  const fs::path root = f.options.out / "airplane";
  testing::WriteTextFile(root / "transforms_val.json", "{}");
  json manifest = ReadJsonFile(root / "manifest.json");
  manifest["files"]["transforms_val.json"] = Sha256File(root / "transforms_val.json");
  WriteJsonFile(root / "manifest.json", manifest);
  fs::create_directories(root / "empty");  // holds nothing to lose
  GenerateScene(f.options, "airplane");
  EXPECT_FALSE(fs::exists(root / "transforms_val.json"));
  EXPECT_FALSE(fs::exists(root / "empty"));
  EXPECT_TRUE(fs::exists(root / "manifest.json"));
}

// A rerun deletes only what datagen wrote: a scene folder holding anything its manifest does not
// list (notes, a training run) is refused, naming it, and nothing is touched.
TEST(Generator, RerunRefusesAFolderHoldingFilesItDidNotWrite) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  GenerateScene(f.options, "airplane");
  const fs::path root = f.options.out / "airplane";
  const std::string manifest = testing::ReadTextFile(root / "manifest.json");
  testing::WriteTextFile(root / "runs" / "r1" / "results.json", "{}");
  testing::WriteTextFile(root / "my_notes.txt", "keep");
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, root.string() + ": holds my_notes.txt and 1 more")) << error;
  EXPECT_TRUE(Contains(error, "did not write")) << error;
  EXPECT_TRUE(Contains(error, "move it out of the folder, or choose another --out")) << error;
  EXPECT_EQ(testing::ReadTextFile(root / "my_notes.txt"), "keep");
  EXPECT_EQ(testing::ReadTextFile(root / "runs" / "r1" / "results.json"), "{}");
  EXPECT_EQ(testing::ReadTextFile(root / "manifest.json"), manifest);
  EXPECT_FALSE(fs::exists(f.options.out / "airplane.partial"));
  // Inside one of datagen's own folders, and a link, too.
  fs::remove(root / "my_notes.txt");
  fs::remove_all(root / "runs");
  testing::WriteTextFile(root / "images" / "mine.png", "x");
  EXPECT_TRUE(Contains(ErrorOf([&] { GenerateScene(f.options, "airplane"); }),
                       ": holds images/mine.png, which"));
  fs::remove(root / "images" / "mine.png");
  fs::create_symlink(f.dir / "fixture", root / "link");
  const std::string link = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(link, ": holds link,")) << link;
  EXPECT_TRUE(fs::exists(f.dir / "fixture" / "render_info.json"));
  fs::remove(root / "link");
  // One of datagen's own files, edited since: no longer its to delete.
  const fs::path transforms = root / "transforms_train.json";
  const std::string original = testing::ReadTextFile(transforms);
  testing::WriteTextFile(transforms, original + " ");
  const std::string edited = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(edited, ": holds transforms_train.json (changed since datagen wrote it),"))
      << edited;
  EXPECT_EQ(testing::ReadTextFile(transforms), original + " ");
  testing::WriteTextFile(transforms, original);
  GenerateScene(f.options, "airplane");  // only its own files again
  EXPECT_NE(testing::ReadTextFile(root / "manifest.json"), manifest);  // new timings
}

// A file that appears while Blender renders is kept: the move refuses and keeps the new scene.
TEST(Generator, RerunKeepsAFileThatAppearedDuringTheRender) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  GenerateScene(f.options, "airplane");
  const fs::path root = f.options.out / "airplane";
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture",
                                       "echo late > '" + (root / "late.txt").string() + "'\n")
                          .string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, ": holds late.txt, which")) << error;
  EXPECT_EQ(testing::ReadTextFile(root / "late.txt"), "late\n");
  EXPECT_TRUE(fs::exists(root / "manifest.json"));
  EXPECT_TRUE(fs::exists(f.options.out / "airplane.partial" / "manifest.json"));
}

TEST(Generator, FailingBlenderNamesSceneFrameErrorAndLogAndKeepsThePreviousOutput) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  GenerateScene(f.options, "airplane");  // a previous good run
  const std::string before = testing::ReadTextFile(f.options.out / "airplane" / "manifest.json");

  f.options.blender = WriteFakeBlender(f.dir.path(), "",
                                       "echo 'HDR4D_RENDERING 1 6 hdr/cam00_t0000.exr'\n"
                                       "echo 'HDR4D_RENDERED 1 6 hdr/cam00_t0000.exr'\n"
                                       "echo 'HDR4D_RENDERING 2 6 hdr/cam00_t0001.exr'\n"
                                       "echo 'Traceback (most recent call last):' >&2\n"
                                       "echo 'ValueError: boom' >&2\necho 'Blender quit'\nexit 1\n")
                          .string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, "scene 'airplane'")) << error;
  EXPECT_TRUE(Contains(error, "exit code 1")) << error;
  EXPECT_TRUE(Contains(error, "frame 2/6 (hdr/cam00_t0001.exr)")) << error;
  EXPECT_TRUE(Contains(error, "ValueError: boom")) << error;
  const fs::path log = f.options.out / "airplane.partial" / "blender.log";
  EXPECT_TRUE(Contains(error, log.string())) << error;
  EXPECT_TRUE(Contains(testing::ReadTextFile(log), "ValueError: boom"));
  // The previous dataset is untouched.
  EXPECT_EQ(testing::ReadTextFile(f.options.out / "airplane" / "manifest.json"), before);
}

TEST(Generator, FailureBeforeTheFirstFrameSaysSo) {
  Fixture f;
  f.options.blender =
      WriteFakeBlender(f.dir.path(), "", "echo 'Error: no scene' >&2\nexit 2\n").string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, "(exit code 2) while building the scene: Error: no scene")) << error;
  EXPECT_FALSE(fs::exists(f.options.out / "airplane"));
}

TEST(Generator, MissingRenderInfoExrOrPointsIsAnErrorNamingTheFile) {
  {
    Fixture f;
    f.options.blender = WriteFakeBlender(f.dir.path(), "", "exit 0\n").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "render_info.json: Blender exited without writing it")) << error;
  }
  {
    Fixture f;
    WriteFixture(f.dir / "fixture", f.preset, /*write_exrs=*/false);
    f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "scene 'airplane': frame")) << error;
    EXPECT_TRUE(Contains(error, "without writing")) << error;
    EXPECT_TRUE(Contains(error, ".exr")) << error;
  }
  {
    Fixture f;
    WriteFixture(f.dir / "fixture", f.preset);
    fs::remove(f.dir / "fixture" / "points_t0.bin");
    f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "points_t0.bin")) << error;
  }
}

// The official HDR-4DGS loader drops, when it subsamples, every point whose time is not
// strictly inside (0, 1): a script that reported such a time is an error naming the file.
TEST(Generator, PointTimesOutsideZeroOneAreAnErrorNamingTheFile) {
  for (const float t : {0.0f, 1.0f, -0.5f}) {
    Fixture f;
    WriteFixture(f.dir / "fixture", f.preset, true, false, t);
    f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "points_t0.bin")) << error;
    EXPECT_TRUE(Contains(error, "outside (0, 1)")) << error;
    EXPECT_FALSE(fs::exists(f.options.out / "airplane"));
  }
  Fixture f;  // a reported sample time outside (0, 1)
  WriteFixture(f.dir / "fixture", f.preset);
  json info = ReadJsonFile(f.dir / "fixture" / "render_info.json");
  info["points"]["times"] = {0.0, 0.75};
  WriteJsonFile(f.dir / "fixture" / "render_info.json", info);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, "render_info.json")) << error;
  EXPECT_TRUE(Contains(error, "inside (0, 1)")) << error;
}

TEST(Generator, CorruptExrOrBadRenderInfoIsAnError) {
  {
    Fixture f;
    WriteFixture(f.dir / "fixture", f.preset, true, /*corrupt_exrs=*/true);
    f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "scene 'airplane': frame")) << error;
    EXPECT_TRUE(Contains(error, "hdr/cam00_t000")) << error;
  }
  {
    Fixture f;
    WriteFixture(f.dir / "fixture", f.preset);
    json info = ReadJsonFile(f.dir / "fixture" / "render_info.json");
    info["renders"].erase(info["renders"].begin());
    WriteJsonFile(f.dir / "fixture" / "render_info.json", info);
    f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "5 renders reported, 6 planned")) << error;
  }
  {
    Fixture f;
    WriteFixture(f.dir / "fixture", f.preset);
    json info = ReadJsonFile(f.dir / "fixture" / "render_info.json");
    info["renders"][2]["transform_matrix"] = json::array({1, 2, 3});
    WriteJsonFile(f.dir / "fixture" / "render_info.json", info);
    f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
    const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
    EXPECT_TRUE(Contains(error, "render 2: transform_matrix")) << error;
  }
}

TEST(Generator, MissingBlenderFailsBeforeTouchingTheOutput) {
  Fixture f;
  f.options.blender = (f.dir / "no-blender").string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, "Blender not found")) << error;
  EXPECT_FALSE(fs::exists(f.options.out));
}

TEST(Generator, RefusesAFolderItDidNotWrite) {
  Fixture f;
  testing::WriteTextFile(f.options.out / "airplane" / "precious.txt", "mine");
  f.options.blender = WriteFakeBlender(f.dir.path(), "", "exit 0\n").string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, "not the output of a previous `hdr4d datagen` run")) << error;
  EXPECT_EQ(testing::ReadTextFile(f.options.out / "airplane" / "precious.txt"), "mine");
  // Nor a work folder that is not one of ours.
  fs::remove_all(f.options.out / "airplane");
  testing::WriteTextFile(f.options.out / "airplane.partial" / "precious.txt", "mine");
  const std::string partial = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(partial, "not a datagen work folder")) << partial;
}

TEST(Generator, UnwritableOutputIsAnError) {
  Fixture f;
  testing::WriteTextFile(f.dir / "file", "x");
  f.options.out = f.dir / "file" / "sub";
  f.options.blender = WriteFakeBlender(f.dir.path(), "", "exit 0\n").string();
  const std::string error = ErrorOf([&] { GenerateScene(f.options, "airplane"); });
  EXPECT_TRUE(Contains(error, "cannot create the output folder")) << error;
  EXPECT_TRUE(Contains(error, "file/sub/airplane.partial")) << error;
}

TEST(Generator, LdrSynthesisIsTheScenesUnlessSet) {
  DatagenOptions o;
  o.seed = 7;
  const DatasetSynthesisOptions hook = o.LdrFor("hook");
  EXPECT_EQ(hook.crf, "filmic");
  EXPECT_EQ(hook.noise.full_well, 20000);
  EXPECT_EQ(hook.noise.read_sigma, 0.002);
  EXPECT_EQ(hook.noise.seed, 7u);
  const DatasetSynthesisOptions studio = o.LdrFor("studio");
  EXPECT_EQ(studio.crf, "naka-rushton:0.2,2.2");
  EXPECT_EQ(studio.noise.full_well, 0);
  EXPECT_EQ(studio.noise.read_sigma, 0);
  o.crf = "gamma";
  o.read_sigma = 0.01;
  EXPECT_EQ(o.LdrFor("studio").crf, "gamma");
  EXPECT_EQ(o.LdrFor("studio").noise.read_sigma, 0.01);
  EXPECT_EQ(o.LdrFor("studio").noise.full_well, 0);
}

// What Blender leaves for a capture of the ci room with 3 cameras: every render of
// CaptureRenders (static images first) as a small EXR, render_info.json, points.
void WriteCaptureFixture(const fs::path& fixture, const ScenePreset& preset) {
  json renders = json::array();
  int i = 0;
  for (const PlannedRender& r : CaptureRenders(preset)) {
    const double angle = -2.0 + 0.5 * r.camera_id;
    const Eigen::Matrix4d pose = LookAtWorldFromCamGl(
        {4 * std::cos(angle), 4 * std::sin(angle), 1.5}, {0, 0, 0.5}, Eigen::Vector3d::UnitZ());
    json m = json::array();
    for (int row = 0; row < 4; ++row)
      m.push_back({pose(row, 0), pose(row, 1), pose(row, 2), pose(row, 3)});
    renders.push_back({{"file", r.hdr_file}, {"camera_id", r.camera_id},
                       {"time_index", r.time_index}, {"time", r.time},
                       {"transform_matrix", m}, {"markers", json::array()}});
    WriteImage(fixture / r.hdr_file,
               testing::RandomImage(preset.width, preset.height, 3, 40 + i++, 0.002f, 0.5f),
               {.format = PixelFormat::kFloat});
  }
  WriteJsonFile(fixture / "render_info.json", {{"blender_version", "3.4.1"},
                                               {"script_version", 1},
                                               {"camera_angle_x", preset.camera_angle_x},
                                               {"points", {{"count", 10}}},
                                               {"renders", renders}});
  std::vector<float> points(60, 0.25f);
  std::ofstream(fixture / "points_t0.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(points.data()), points.size() * sizeof(float));
}

struct CaptureFixture {
  TempDir dir;
  DatagenOptions options;
  explicit CaptureFixture(const std::string& unlike = "none", int extra_views = 0,
                          std::vector<double> brackets = {},
                          const std::function<void(DatagenOptions&)>& variant = {}) {
    options.scene = "room";
    options.preset = "ci";
    options.out = dir / "out";
    options.show_progress = false;
    options.capture = true;
    options.cameras = 3;
    options.frames = 2;
    options.unlike_cameras = unlike;
    options.extra_views = extra_views;
    options.brackets = std::move(brackets);
    if (variant) variant(options);
    WriteCaptureFixture(dir / "fixture", CapturePreset(options, "room"));
    options.blender = WriteFakeBlender(dir.path(), dir / "fixture", "").string();
  }
  fs::path Root() const { return options.out / "room"; }
};

TEST(Capture, WritesTheLayoutCalibrateReadsAndTheTruth) {
  CaptureFixture f;
  const SceneResult result = GenerateScene(f.options, "room");
  const fs::path root = f.Root();
  EXPECT_TRUE(result.capture);
  EXPECT_EQ(result.cameras, 3);
  EXPECT_EQ(result.frames, 2);
  EXPECT_EQ(result.brackets, 3);
  EXPECT_EQ(result.renders, 3 + 3 * 2);
  EXPECT_EQ(result.ldr_images, 3 + 3 * 2 * 3);
  EXPECT_FALSE(fs::exists(f.options.out / "room.partial"));
  // The plan asks the script for the capture layout and marks the static renders.
  const json plan = ReadJsonFile(root / "render_plan.json");
  EXPECT_EQ(plan["layout"], "capture");
  EXPECT_EQ(plan["held_out_cameras"], 1);
  EXPECT_EQ(plan["renders"][0]["static"], true);
  EXPECT_EQ(plan["renders"][0]["file"], "truth/static/cam00.exr");
  EXPECT_FALSE(plan["renders"][3].contains("static"));
  // The capture.
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(ReadImage(root / CaptureStaticFile(c)).width(), 48);
    for (int frame = 0; frame < 2; ++frame)
      for (int k = 0; k < 3; ++k)
        EXPECT_TRUE(fs::is_regular_file(root / CaptureBracketFile(c, frame, k))) << c << frame << k;
  }
  EXPECT_EQ(CaptureBracketFile(2, 1, 0), "sequence/cam02/00001_0.png");
  EXPECT_EQ(ReadJsonFile(root / "exposures.json")["brackets"], json({0.125, 2.0, 32.0}));
  EXPECT_EQ(ReadJsonFile(root / "timestamps.json"), json({{"0", 0.0}, {"1", 1.0}}));
  // The truth: a checked dataset whose last camera is the test split, its LDR images the very
  // brackets of alike cameras.
  const Dataset truth = LoadDataset(root / "truth", {.image_check = ImageCheck::kFull});
  EXPECT_EQ(truth.train.size(), 2u * 2u * 3u);
  EXPECT_EQ(truth.test.size(), 1u * 2u * 3u);
  for (const Frame& f : truth.test) EXPECT_EQ(f.camera_id, 2);
  for (const Frame* frame : truth.AllFrames()) {
    const int t = static_cast<int>(std::lround(frame->time));
    EXPECT_EQ(testing::ReadTextFile(frame->image_path),
              testing::ReadTextFile(root / CaptureBracketFile(frame->camera_id, t, frame->exposure_index)))
        << frame->file_path;
  }
  const json cameras = ReadJsonFile(root / "truth" / "cameras.json");
  ASSERT_EQ(cameras["cameras"].size(), 3u);
  const json& cam1 = cameras["cameras"][1];
  EXPECT_EQ(cam1["name"], "cam01");
  EXPECT_EQ(cam1["gain"], json({1.0, 1.0, 1.0}));
  EXPECT_EQ(cam1["hdr_files"]["1"], "hdr/cam01_t0001.exr");
  EXPECT_EQ(cam1["held_out"], false);
  EXPECT_EQ(cameras["cameras"][2]["held_out"], true);
  EXPECT_NEAR(cam1["fx"].get<double>(), 24 / std::tan(kSynCameraAngleX / 2), 1e-9);
  EXPECT_TRUE(fs::exists(root / "truth" / "static" / "cam01.exr"));
  EXPECT_TRUE(fs::exists(root / "truth" / "point3d.ply"));
  EXPECT_FALSE(fs::exists(root / "truth" / "response_cam01.csv"));  // alike responses
  // The true response in calibrate's format: x(128) = 1, the filmic curve's inverse.
  const std::string csv = testing::ReadTextFile(root / "truth" / "response.csv");
  EXPECT_TRUE(Contains(csv, "\n128,1,1,1\n")) << csv.substr(0, 200);
  const json manifest = ReadJsonFile(root / "manifest.json");
  EXPECT_EQ(manifest["mode"], "capture");
  EXPECT_TRUE(manifest["files"].contains("sequence/cam00/00000_0.png"));
  EXPECT_TRUE(manifest["files"].contains("truth/cameras.json"));
  // A rerun replaces it (the manifest names datagen).
  GenerateScene(f.options, "room");
  EXPECT_TRUE(fs::exists(root / "truth" / "cameras.json"));
}

TEST(Capture, UnlikeCamerasRecordTheirOwnGainsAndResponses) {
  CaptureFixture f("both");
  GenerateScene(f.options, "room");
  const fs::path root = f.Root();
  const json cameras = ReadJsonFile(root / "truth" / "cameras.json");
  EXPECT_EQ(cameras["cameras"][0]["gain"], json({1.0, 1.0, 1.0}));
  EXPECT_EQ(cameras["cameras"][0]["response_exponent"], 1.0);
  const json& cam1 = cameras["cameras"][1];
  const double exponent = cam1["response_exponent"].get<double>();
  EXPECT_GE(exponent, 0.9);
  EXPECT_LE(exponent, 1.1);
  EXPECT_NE(exponent, 1.0);
  for (int ch = 0; ch < 3; ++ch) {
    const double g = cam1["gain"][ch].get<double>();
    EXPECT_GT(g, std::exp(-0.3) - 1e-9);
    EXPECT_LT(g, std::exp(0.3) + 1e-9);
  }
  EXPECT_TRUE(fs::exists(root / "truth" / "response_cam01.csv"));
  // Camera 1's bracket is its own record of the radiance, through its gains and its response,
  // not the truth dataset's reference image. The room adds sensor noise, so the mean code is
  // compared, which the noise barely moves.
  const Image hdr = ReadImage(root / "truth" / "hdr" / "cam01_t0000.exr");
  Image gained = hdr;
  for (std::size_t i = 0; i < gained.size(); ++i)
    gained.data()[i] *= static_cast<float>(cam1["gain"][i % 3].get<double>());
  const std::unique_ptr<Crf> base = ParseCrf("filmic");
  const Image bracket = ReadImage(root / CaptureBracketFile(1, 0, 1));
  const Image reference = ReadImage(root / "truth" / "images" / "cam01_t0000_e1.png");
  double expected = 0, got = 0, ref = 0;
  for (std::size_t i = 0; i < hdr.size(); ++i) {
    expected += base->Apply(std::pow(gained.data()[i] * 2.0, exponent));
    got += bracket.data()[i];
    ref += reference.data()[i];
  }
  EXPECT_NEAR(got / expected, 1.0, 0.02);
  EXPECT_GT(std::abs(got / ref - 1.0), 0.02);
}

TEST(Capture, HandHeldViewsAndOwnBracketsAreWritten) {
  CaptureFixture f("none", 2, {0.5, 2, 8});
  const SceneResult result = GenerateScene(f.options, "room");
  const fs::path root = f.Root();
  EXPECT_EQ(result.extra_views, 2);
  EXPECT_EQ(result.renders, 3 + 2 + 3 * 2);
  // Blender renders them as cameras after the rig's, static only.
  const json plan = ReadJsonFile(root / "render_plan.json");
  EXPECT_EQ(plan["renders"][4]["file"], "truth/static/extra01.exr");
  EXPECT_EQ(plan["renders"][4]["camera_id"], 4);
  EXPECT_EQ(plan["renders"][4]["static"], true);
  EXPECT_EQ(plan["cameras"], 3);
  for (int j = 0; j < 2; ++j) EXPECT_TRUE(fs::is_regular_file(root / CaptureExtraFile(j))) << j;
  EXPECT_EQ(CaptureExtraFile(1), "static/extra/extra01.png");
  const json truth = ReadJsonFile(root / "truth" / "cameras.json");
  ASSERT_EQ(truth["extra_views"].size(), 2u);
  EXPECT_EQ(truth["extra_views"][1]["file"], "static/extra/extra01.png");
  EXPECT_EQ(truth["extra_views"][1]["transform_matrix"].size(), 4u);
  // The brackets are the capture's and the truth dataset's exposures.
  EXPECT_EQ(ReadJsonFile(root / "exposures.json")["brackets"], json({0.5, 2.0, 8.0}));
  EXPECT_EQ(truth["exposures"], json({0.5, 2.0, 8.0}));
  const Dataset dataset = LoadDataset(root / "truth");
  for (const Frame* frame : dataset.AllFrames())
    EXPECT_EQ(frame->exposure, (std::vector<double>{0.5, 2, 8})[frame->exposure_index]);
}

// Issue 54's variants: a size of its own, dense brackets one stop apart, a pedestal with dark
// noise, each camera's own lens; what was drawn is in the truth.
TEST(Capture, VariantsGoThroughSizeBracketsPedestalAndLensesAndTheTruthRecordsThem) {
  CaptureFixture f("none", 0, {}, [](DatagenOptions& o) {
    o.width = 80;
    o.height = 48;
    o.dense_brackets = 5;
    o.black_level = 16;
    o.black_noise = 1.5;
    o.lenses = "both";
  });
  const SceneResult result = GenerateScene(f.options, "room");
  const fs::path root = f.Root();
  EXPECT_EQ(result.brackets, 5);
  const Image still = ReadImage(root / CaptureStaticFile(1));
  EXPECT_EQ(still.width(), 80);
  EXPECT_EQ(still.height(), 48);
  EXPECT_EQ(ReadJsonFile(root / "exposures.json")["brackets"], json({0.5, 1.0, 2.0, 4.0, 8.0}));
  const json truth = ReadJsonFile(root / "truth" / "cameras.json");
  EXPECT_EQ(truth["lenses"], "both");
  EXPECT_EQ(truth["noise"]["black_level_codes"], 16.0);
  EXPECT_EQ(truth["noise"]["black_noise_codes"], 1.5);
  for (const json& cam : truth["cameras"]) {
    EXPECT_GE(cam["k1"].get<double>(), 0.03);
    EXPECT_LE(cam["k1"].get<double>(), 0.10);
    EXPECT_GE(cam["vignetting"].get<double>(), 0.05);
    EXPECT_LE(cam["vignetting"].get<double>(), 0.25);
    EXPECT_EQ(cam["width"], 80);
  }
  EXPECT_NE(truth["cameras"][0]["k1"], truth["cameras"][1]["k1"]);
  // Codes at or below the pedestal are no exposure in the true response; code 128 is 1.
  const std::string csv = testing::ReadTextFile(root / "truth" / "response.csv");
  EXPECT_TRUE(Contains(csv, "\n16,0,0,0\n")) << csv.substr(0, 300);
  EXPECT_TRUE(Contains(csv, "\n128,1,1,1\n"));
  // The brackets are the cameras' own records, not the truth dataset's pinhole LDR images, and
  // nothing falls far below the pedestal (six widths of its noise).
  const Image bracket = ReadImage(root / CaptureBracketFile(0, 0, 0));
  EXPECT_NE(testing::ReadTextFile(root / CaptureBracketFile(0, 0, 2)),
            testing::ReadTextFile(root / "truth" / "images" / "cam00_t0000_e2.png"));
  float lowest = 1;
  for (std::size_t i = 0; i < bracket.size(); ++i) lowest = std::min(lowest, bracket.data()[i]);
  EXPECT_GE(lowest * 255, 16 - 6 * 1.5);
  const json manifest = ReadJsonFile(root / "manifest.json");
  EXPECT_EQ(manifest["capture"]["lenses"], "both");
  EXPECT_EQ(manifest["capture"]["black_level_codes"], 16.0);
  EXPECT_EQ(manifest["render"]["height"], 48);
}

TEST(Capture, VariantFlagsAreCheckedAndNeedACapture) {
  DatagenOptions o;
  o.out = "x";
  o.scene = "room";
  o.width = 320;
  o.height = 240;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--size describes a capture rig"));
  o.capture = true;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
  o.height = 20;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "datagen: --size 320x20: use 64x48 to 8192x8192");
  o.height = 240;
  o.dense_brackets = 2;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--dense-brackets 2: use 3 to 20"));
  o.dense_brackets = 12;
  o.brackets = {1, 2};
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "give one"));
  o.brackets = {};
  o.black_level = 65;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--black-level 65: use 0 to 64 codes"));
  o.black_level = 16;
  o.black_noise = -1;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "noise -1: use 0 to 16 codes"));
  o.black_noise = 1.5;
  o.lenses = "fisheye";
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }),
            "datagen: --lenses fisheye: use none, distortion, vignetting or both");
  o.lenses = "distortion";
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
  EXPECT_EQ(CapturePreset(o, "room").exposures.size(), 12u);
  EXPECT_EQ(CapturePreset(o, "room").height, 240);
  // --width alone has the same bounds on the size it gives (room: 3/4 of the width).
  o.height = 0;
  o.width = 2;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }),
            "datagen: --width 2 gives 2x2 capture images (the scene's aspect): use 64x48 to "
            "8192x8192, as --size");
  o.width = 8200;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--width 8200 gives 8200x6150 capture"));
  o.width = 64;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
  EXPECT_EQ(CapturePreset(o, "room").height, 48);
  // Through the command line: one line, exit 1, nothing written.
  TempDir dir;
  for (const std::string flags : {"--size 320", "--size 320x", "--black-level 16:x", "--lenses odd"}) {
    const testing::CommandResult cli = testing::RunHdr4d(
        "datagen --capture --scene room " + flags + " --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(cli.exit_code, 1) << flags;
    EXPECT_TRUE(Contains(cli.err, flags.substr(0, flags.find(' ')))) << flags << ": " << cli.err;
    EXPECT_FALSE(fs::exists(dir / "o"));
  }
  // --size and --width both set the width: refused, not one silently kept.
  const testing::CommandResult both = testing::RunHdr4d(
      "datagen --capture --scene room --size 64x48 --width 100 --out '" + (dir / "o").string() +
      "'");
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_TRUE(Contains(both.err, "--size and --width both set the image width")) << both.err;
  EXPECT_FALSE(fs::exists(dir / "o"));
  const testing::CommandResult help = testing::RunHdr4d("datagen --help");
  for (const char* flag : {"--size", "--dense-brackets", "--black-level", "--lenses"})
    EXPECT_TRUE(Contains(help.out, flag)) << flag;
}

TEST(Capture, BadFlagsAreClearErrors) {
  DatagenOptions o;
  o.out = "x";
  o.scene = "room";
  o.cameras = 4;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }),
            "datagen: --cameras describes a capture rig and needs --capture (a dataset keeps its "
            "scene's own cameras and timestamps)");
  o.cameras = 0;
  o.frames = 3;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--frames describes a capture rig"));
  o.frames = 0;
  o.unlike_cameras = "gains";
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--unlike-cameras describes a capture rig"));
  o.capture = true;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
  o.unlike_cameras = "sometimes";
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }),
            "datagen: --unlike-cameras sometimes: use none, gains, responses or both");
  o.unlike_cameras = "none";
  o.scene = "all";
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--capture renders one scene; give --scene"));
  o.scene = "room";
  for (int bad : {1, -1, 13}) {
    o.cameras = bad;
    EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }),
                         fmt::format("--cameras {}: a capture rig has 2 to 12 cameras", bad)));
  }
  o.cameras = 12;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
  o.frames = 1;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--frames 1: a capture needs at least 2"));
  o.frames = 0;
  o.extra_views = 101;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--extra-views 101: use 0 to 100"));
  o.extra_views = 0;
  o.brackets = {2};
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--brackets: 1 exposure time; a capture needs at least two"));
  o.brackets = {0.5, 2, 2};
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--brackets: 2 after 2: give the times in increasing order"));
  o.brackets = {0.5, -1};
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--brackets: -1 is not a positive exposure time"));
  o.brackets = {0.5, 2};
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
  o.capture = false;
  o.cameras = 0;
  o.unlike_cameras = "none";
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--brackets describes a capture rig"));
  // Through the command line: one line, exit 1, nothing written.
  TempDir dir;
  const testing::CommandResult cli = testing::RunHdr4d(
      "datagen --scene room --cameras 3 --out '" + (dir / "o").string() + "'");
  EXPECT_EQ(cli.exit_code, 1);
  EXPECT_TRUE(Contains(cli.err, "--cameras describes a capture rig and needs --capture")) << cli.err;
  EXPECT_FALSE(fs::exists(dir / "o"));
  const testing::CommandResult mode = testing::RunHdr4d(
      "datagen --capture --scene room --unlike-cameras odd --out '" + (dir / "o").string() + "'");
  EXPECT_EQ(mode.exit_code, 1);
  EXPECT_TRUE(Contains(mode.err, "--unlike-cameras")) << mode.err;
}

TEST(Generator, OptionsAreValidated) {
  DatagenOptions o;
  o.out = "x";
  o.scene = "unicorn";
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "unknown scene 'unicorn'"));
  o.scene = "all";
  o.preset = "tiny";
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "unknown preset 'tiny'"));
  o.preset = "ci";
  o.out.clear();
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--out"));
  o.out = "x";
  o.threads = -1;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--threads"));
  o.threads = 0;
  o.samples = -2;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--samples"));
  o.samples = 0;
  o.width = -1;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--width"));
  o.width = 0;
  o.points = -1;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }), "--points"));
  o.points = 0;
  o.crf = "bogus";
  EXPECT_FALSE(ErrorOf([&] { o.Validate(); }).empty());
  o.crf = "filmic";
  o.read_sigma = -1;
  EXPECT_FALSE(ErrorOf([&] { o.Validate(); }).empty());
  o.read_sigma = 0;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
}

// Huge sizes are refused before Blender is asked: at most 8192 pixels a side, and a scene's
// renders at most 16 GiB of float RGB (a dataset's or a capture's).
TEST(Generator, HugeImagesAreRefused) {
  DatagenOptions o;
  o.out = "x";
  o.preset = "ci";
  o.width = 8192;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");  // every scene
  o.width = 100000;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }),
            "datagen: --width 100000: at most 8192 pixels (a float RGB frame of 8192x8192 is 0.8 "
            "GB, held a few times over by Cycles and datagen)");
  o.scene = "airplane";
  o.preset = "paper";
  o.width = 0;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");  // 350 renders of 800x800
  o.width = 4096;
  EXPECT_TRUE(Contains(ErrorOf([&] { o.Validate(); }),
                       "scene 'airplane': 350 renders of 4096x4096 are 65.6 GiB of float RGB"));
  o = {};
  o.out = "x";
  o.scene = "room";
  o.preset = "ci";
  o.capture = true;
  o.cameras = 12;
  o.frames = 100000;
  const std::string capture = ErrorOf([&] { o.Validate(); });
  EXPECT_TRUE(Contains(capture, "renders of 48x36 are")) << capture;
  EXPECT_TRUE(Contains(capture, "--frames")) << capture;
  // Through the command line: one line, exit 1, nothing written, Blender never started.
  TempDir dir;
  const testing::CommandResult cli = testing::RunHdr4d(
      "datagen --scene marker --preset ci --width 100000 --blender /bin/false --out '" +
      (dir / "o").string() + "'");
  EXPECT_EQ(cli.exit_code, 1);
  EXPECT_TRUE(Contains(cli.err, "--width: expected an integer in [0, 8192], got '100000'"))
      << cli.err;
  EXPECT_TRUE(Contains(testing::RunHdr4d("datagen --help").out, "at most 8192, and a scene's"));
  EXPECT_FALSE(fs::exists(dir / "o"));
}

}  // namespace
}  // namespace hdr4d::datagen
