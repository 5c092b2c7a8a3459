// The driver with a stand-in for Blender: a shell script that copies prepared files (renders,
// points, render_info.json) next to the plan, or fails the way Blender can. These run without
// Blender; blender_scenes_test.cpp runs the real one.
#include "datagen/generator.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/dataset.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/ply.h"
#include "datagen/scene_presets.h"
#include "datagen/sha256.h"
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
// 50 surface points and render_info.json with cameras on a ring looking at the origin.
void WriteFixture(const fs::path& fixture,
                  const ScenePreset& preset,
                  bool write_exrs = true,
                  bool corrupt_exrs = false) {
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
                                               {"script_version", 1},
                                               {"camera_angle_x", preset.camera_angle_x},
                                               {"points", {{"count", 50}}},
                                               {"renders", renders}});
  std::vector<float> points;
  for (int p = 0; p < 50; ++p)
    points.insert(points.end(), {0.01f * p, -0.02f * p, 0.5f, 0.2f, 0.4f, 0.6f});
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
  for (float t : cloud.times) EXPECT_EQ(t, 0.0f);
  EXPECT_NEAR(cloud.positions[10].x(), 0.1f, 1e-6);

  const json manifest = ReadJsonFile(root / "manifest.json");
  EXPECT_EQ(manifest["generator"], "hdr4d datagen");
  EXPECT_EQ(manifest["scene"], "airplane");
  EXPECT_EQ(manifest["preset"], "ci");
  EXPECT_EQ(manifest["seed"], 3);
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

TEST(Generator, RerunReplacesItsOwnPreviousOutput) {
  Fixture f;
  WriteFixture(f.dir / "fixture", f.preset);
  f.options.blender = WriteFakeBlender(f.dir.path(), f.dir / "fixture", "").string();
  std::vector<std::string> done;
  const auto results = Generate(f.options, [&](const SceneResult& r) { done.push_back(r.scene); });
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(done, std::vector<std::string>{"airplane"});
  testing::WriteTextFile(f.options.out / "airplane" / "stale.txt", "from before");
  GenerateScene(f.options, "airplane");
  EXPECT_FALSE(fs::exists(f.options.out / "airplane" / "stale.txt"));
  EXPECT_TRUE(fs::exists(f.options.out / "airplane" / "manifest.json"));
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
  o.crf = "bogus";
  EXPECT_FALSE(ErrorOf([&] { o.Validate(); }).empty());
  o.crf = "filmic";
  o.read_sigma = -1;
  EXPECT_FALSE(ErrorOf([&] { o.Validate(); }).empty());
  o.read_sigma = 0;
  EXPECT_EQ(ErrorOf([&] { o.Validate(); }), "");
}

}  // namespace
}  // namespace hdr4d::datagen
