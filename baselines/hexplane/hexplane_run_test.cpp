// A HexPlane run as a complete citizen: a checkpoint that round-trips bit for bit, --resume that
// continues exactly, renders at any time and along the orbit, and the HDR metrics of Table 1
// (with the log-log slope) in results.json for the HDR methods.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>

#include "baselines/hexplane/hexplane_render.h"
#include "baselines/hexplane/hexplane_run.h"
#include "baselines/hexplane/hexplane_train.h"
#include "baselines/hexplane/hexplane_train_state.h"
#include "core/dataset/demo_scene.h"
#include "core/files/json_util.h"
#include "core/radiometry/exposure_stack.h"
#include "core/util/error.h"
#include "method/run/gaussian_scene.h"
#include "tests/testing.h"

namespace hdr4d::baselines::hexplane {
namespace {
namespace fs = std::filesystem;
using hdr4d::testing::ErrorOf;
using hdr4d::testing::TempDir;

std::string Bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A training checkpoint's bytes with the training seconds (wall time) zeroed: the model, the
// optimiser and the trainer's generator and pixel order.
std::string WithoutTime(const fs::path& checkpoint) {
  const LoadedHexPlaneRun run = LoadHexPlaneRun(checkpoint.parent_path());
  HexPlaneModel model;
  PlainAdam adam(run.config.beta1, run.config.beta2);
  HexPlaneTrainState state = LoadTrainingCheckpoint(checkpoint, run.config, &model, &adam);
  state.seconds = 0;
  const fs::path copy = checkpoint.parent_path() / "untimed.bin";
  SaveTrainingCheckpoint(copy, model, adam, state);
  return Bytes(copy);
}

void MakeLdrScene(const fs::path& root) {
  method::GaussianSceneOptions s;
  s.size = 20;
  s.num_gaussians = 10;
  s.num_cameras = 4;
  s.num_timestamps = 3;
  method::MakeGaussianScene(s, root);
}

// The analytic HDR demo scene (point3d.ply, EXR truth, LDR brackets).
void MakeHdrScene(const fs::path& root) {
  DemoSceneOptions s;
  s.width = s.height = 20;
  s.num_timestamps = 3;
  s.num_cameras = 3;
  s.samples_per_axis = 1;
  MakeDemoScene(s, root);
  DatasetSynthesisOptions ldr;
  ldr.noise.seed = 1;
  SynthesizeDatasetLdr(root, ldr);
}

HexPlaneTrainOptions SmallRun(const fs::path& scene, const fs::path& run, int iterations) {
  HexPlaneTrainOptions o;
  o.data = scene;
  o.out = run;
  o.progress = false;
  o.threads = 2;  // the ray lanes sum per thread: equal runs need equal thread counts
  o.iterations = iterations;
  o.batch_rays = 256;
  o.voxels_init = 10 * 10 * 10;
  o.voxels_final = 16 * 16 * 16;
  o.time_grid_init = 3;
  o.time_grid_final = 4;
  return o;
}

// HDR-HexPlane with LDR+HDR supervision, as SmallRun.
HexPlaneTrainOptions SmallHdrHexPlaneRun(const fs::path& scene, const fs::path& run, int iterations) {
  HexPlaneTrainOptions o = SmallRun(scene, run, iterations);
  o.method = "hdr-hexplane";
  o.supervision = "ldr+hdr";
  return o;
}

// Interrupted between the schedules' events (upsampling after iterations 4, 7, 11, occupancy
// after 5, 10, 12 of 30; counted from 0) and resumed: the same checkpoint as a run never stopped.
TEST(HexPlaneRun, ResumeContinuesExactly) {
  TempDir dir;
  MakeLdrScene(dir / "scene");
  const HexPlaneTrainSummary straight = TrainHexPlane(SmallRun(dir / "scene", dir / "straight", 30));
  for (int stop : {5, 9}) {
    const fs::path run = dir / fmt::format("split{}", stop);
    HexPlaneTrainOptions first = SmallRun(dir / "scene", run, 30);
    first.stop_after = stop;
    EXPECT_EQ(TrainHexPlane(first).iterations, stop);
    EXPECT_FALSE(fs::exists(run / "results.json"));
    HexPlaneTrainOptions rest;  // everything else from the run's config.json
    rest.out = run;
    rest.resume = true;
    rest.progress = false;
    rest.threads = 2;
    const HexPlaneTrainSummary resumed = TrainHexPlane(rest);
    EXPECT_EQ(resumed.iterations, 30);
    EXPECT_EQ(WithoutTime(run / "checkpoint.bin"), WithoutTime(dir / "straight" / "checkpoint.bin"))
        << "stopped at " << stop;
    EXPECT_EQ(resumed.test_metrics, straight.test_metrics);
    EXPECT_EQ(ReadJsonFile(run / "config.json"), ReadJsonFile(dir / "straight" / "config.json"));
  }
}

// Save, load, save: the same bytes, model and trainer state both.
// A learned background (--grid-background environment) is trained, recorded in the run's
// configuration and carried by the checkpoint; a model without one reads as before.
TEST(HexPlaneRun, ALearnedBackgroundIsTrainedSavedAndReadBack) {
  TempDir dir;
  MakeLdrScene(dir / "scene");
  HexPlaneTrainOptions o = SmallRun(dir / "scene", dir / "run", 40);
  o.background_model = "environment";
  o.stop_after = 7;
  TrainHexPlane(o);
  const LoadedHexPlaneRun run = LoadHexPlaneRun(dir / "run");
  EXPECT_EQ(run.config.background_model, "environment");
  ASSERT_EQ(run.model.background.size(), 27u);
  bool moved = false;  // it starts uniform: only the degree-0 terms are non-zero
  for (std::size_t i = 3; i < run.model.background.size(); ++i)
    moved = moved || run.model.background[i] != 0.0f;
  EXPECT_TRUE(moved);
  HexPlaneModel model;
  PlainAdam adam(run.config.beta1, run.config.beta2);
  const HexPlaneTrainState state =
      LoadTrainingCheckpoint(dir / "run" / "checkpoint.bin", run.config, &model, &adam);
  EXPECT_EQ(model.background, run.model.background);
  SaveTrainingCheckpoint(dir / "again.bin", model, adam, state);
  EXPECT_TRUE(Bytes(dir / "again.bin") == Bytes(dir / "run" / "checkpoint.bin"));
}

TEST(HexPlaneRun, CheckpointRoundTripsBitForBit) {
  TempDir dir;
  MakeLdrScene(dir / "scene");
  HexPlaneTrainOptions o = SmallRun(dir / "scene", dir / "run", 40);
  o.stop_after = 7;
  TrainHexPlane(o);
  const LoadedHexPlaneRun run = LoadHexPlaneRun(dir / "run");  // the model part alone
  HexPlaneModel model;
  PlainAdam adam(run.config.beta1, run.config.beta2);
  const HexPlaneTrainState state =
      LoadTrainingCheckpoint(dir / "run" / "checkpoint.bin", run.config, &model, &adam);
  EXPECT_EQ(state.iteration, 7);
  EXPECT_TRUE(state.in_epoch);
  SaveTrainingCheckpoint(dir / "again.bin", model, adam, state);
  EXPECT_TRUE(Bytes(dir / "again.bin") == Bytes(dir / "run" / "checkpoint.bin"));
  EXPECT_EQ(model.mlp, run.model.mlp);
  // A model-only file, a cut one and one with stray bytes are refused by name.
  run.model.Save(dir / "model.bin");
  EXPECT_NE(ErrorOf([&] { LoadTrainingCheckpoint(dir / "model.bin", run.config, &model, &adam); })
                .find("no training state"),
            std::string::npos);
  const std::string bytes = Bytes(dir / "again.bin");
  std::ofstream(dir / "cut.bin", std::ios::binary) << bytes.substr(0, bytes.size() - 5);
  EXPECT_NE(ErrorOf([&] { LoadTrainingCheckpoint(dir / "cut.bin", run.config, &model, &adam); })
                .find("cut.bin"),
            std::string::npos);
  std::ofstream(dir / "long.bin", std::ios::binary) << bytes << "x";
  EXPECT_NE(ErrorOf([&] { LoadTrainingCheckpoint(dir / "long.bin", run.config, &model, &adam); })
                .find("unexpected bytes"),
            std::string::npos);
}

TEST(HexPlaneRun, ResumeRefusesOtherSettingsAndMissingRuns) {
  TempDir dir;
  MakeLdrScene(dir / "scene");
  HexPlaneTrainOptions o = SmallRun(dir / "scene", dir / "none", 10);
  o.resume = true;
  EXPECT_NE(ErrorOf([&] { TrainHexPlane(o); }).find("to resume from"), std::string::npos);
  o = SmallRun(dir / "scene", dir / "run", 10);
  o.stop_after = 3;
  TrainHexPlane(o);
  o.stop_after = 0;
  o.resume = true;
  o.iterations = 20;  // another schedule: not the same run
  EXPECT_NE(ErrorOf([&] { TrainHexPlane(o); }).find("hexplane.iterations"), std::string::npos);
  o.iterations = 10;  // the same value given again is fine
  EXPECT_EQ(TrainHexPlane(o).iterations, 10);
}

// --time and --video through the run folder, with --timing for the split.
TEST(HexPlaneRun, RendersAtAnyTimeAndAlongTheOrbit) {
  TempDir dir;
  MakeLdrScene(dir / "scene");
  TrainHexPlane(SmallRun(dir / "scene", dir / "run", 10));
  EXPECT_EQ(RenderHexPlaneRun({.run = dir / "run", .time = 0.37f, .camera_index = 1}), 1);
  EXPECT_TRUE(fs::exists(dir / "run" / "renders" / "time" / "test_cam001_t0.3700.png"));
  EXPECT_EQ(RenderHexPlaneRun({.run = dir / "run", .video_frames = 3}), 3);
  EXPECT_TRUE(fs::exists(dir / "run" / "video" / "frame_0002.png"));
  const int n = RenderHexPlaneRun({.run = dir / "run", .timing = dir / "timing.json"});
  EXPECT_GT(n, 0);
  EXPECT_EQ(ReadJsonFile(dir / "timing.json")["views"], n);
  EXPECT_NE(ErrorOf([&] { RenderHexPlaneRun({.run = dir / "run", .time = 0.5f, .camera_index = 99}); })
                .find("--camera 99"),
            std::string::npos);
}

// HDR-HexPlane with LDR+HDR supervision and HexPlane* on a scene with HDR truth: results.json
// holds the LDR and Table 1's HDR metrics and the log-log slope; HexPlane* has no LDR output.
TEST(HexPlaneRun, HdrMethodsReportTableOneMetricsAndTheSlope) {
  TempDir dir;
  MakeHdrScene(dir / "scene");
  HexPlaneTrainOptions o = SmallHdrHexPlaneRun(dir / "scene", dir / "hdr", 30);
  const HexPlaneTrainSummary s = TrainHexPlane(o);
  for (const char* key : {"psnr", "ssim", "flip", "mu_psnr", "mu_ssim", "pu21_psnr", "hdr_flip", "hdr_flip_aligned",
                          "hdr_log_slope", "hdr_log_corr"})
    EXPECT_TRUE(s.test_metrics.contains(key)) << key << " in " << s.test_metrics.dump();
  const nlohmann::json config = ReadJsonFile(dir / "hdr" / "config.json");
  EXPECT_TRUE(config["hexplane"]["hdr_loss"].get<bool>());
  EXPECT_NE(config["hexplane"]["center"], nlohmann::json({0, 0, 0}));  // around point3d.ply
  o = SmallRun(dir / "scene", dir / "star", 20);
  o.method = "hexplane";
  o.supervision = "hdr";  // HexPlane*: the table's HexPlane row with HDR supervision
  const HexPlaneTrainSummary star = TrainHexPlane(o);
  EXPECT_EQ(ReadJsonFile(dir / "star" / "config.json")["method"], "hexplane-hdr");
  EXPECT_TRUE(star.test_metrics.contains("mu_psnr"));
  EXPECT_FALSE(star.test_metrics.contains("psnr"));
  const int written = RenderHexPlaneRun({.run = dir / "star", .out = dir / "star_renders"});
  for (const auto& e : fs::directory_iterator(dir / "star_renders"))
    EXPECT_EQ(e.path().extension(), ".exr") << e.path();
  EXPECT_GT(written, 0);
}

// The test split's brackets of one shot rendered together (BracketRenderer) are the images of
// one view at a time, in any order; each shot is rendered once.
TEST(HexPlaneRun, BracketsOfAShotRenderAsSingleViews) {
  TempDir dir;
  MakeHdrScene(dir / "scene");
  TrainHexPlane(SmallHdrHexPlaneRun(dir / "scene", dir / "run", 10));
  const LoadedHexPlaneRun run = LoadHexPlaneRun(dir / "run");
  std::vector<BracketRenderer::ViewAt> views;
  for (const Frame& f : run.dataset.test) views.push_back({f.camera, float(f.time), f.exposure});
  BracketRenderer renderer(run.model, views);
  std::vector<float> ldr, hdr, single_ldr, single_hdr;
  for (std::size_t k = views.size(); k-- > 0;) {  // backwards: any order works
    renderer.Render(k, &ldr, &hdr);
    RenderView(run.model, views[k].camera, views[k].time01, views[k].exposure, -1, &single_ldr,
               &single_hdr);
    ASSERT_FALSE(ldr.empty());
    EXPECT_EQ(ldr, single_ldr) << "view " << k;
    EXPECT_EQ(hdr, single_hdr) << "view " << k;
  }
  std::set<std::pair<float, double>> shots;  // the demo's test views: (time, camera centre x)
  for (const auto& v : views) shots.insert({v.time01, v.camera.Center().x()});
  EXPECT_EQ(renderer.shots_rendered(), int(shots.size()));
  EXPECT_LT(renderer.shots_rendered(), int(views.size()));  // brackets shared a march
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
