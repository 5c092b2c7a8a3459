// --camera-correction through the trainer and `hdr4d render` (method/tonemap/camera_correction.h):
// which camera each frame is, exact resume, the record in config.json and the checkpoint, the
// renders of a training camera with its gains and of any other camera without, and the errors.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "core/dataset/demo_scene.h"
#include "core/files/json_util.h"
#include "core/radiometry/exposure_stack.h"
#include "method/run/render_split.h"
#include "method/train/checkpoint.h"
#include "method/train/correction_cameras.h"
#include "method/train/tiny_run_test_util.h"
#include "method/train/trainer.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {
namespace fs = std::filesystem;
using hdr4d::testing::ErrorOf;
using hdr4d::testing::TempDir;

Frame FrameOf(int camera_id, double x) {
  Frame f;
  f.camera_id = camera_id;
  f.camera.world_from_cam_gl(0, 3) = x;
  return f;
}

TEST(CorrectionCameras, IdsThenPosesAndOtherCamerasGetNone) {
  Dataset d;
  d.train = {FrameOf(7, 0), FrameOf(2, 1), FrameOf(7, 2), FrameOf(-1, 5), FrameOf(-1, 6),
             FrameOf(-1, 5)};
  d.test = {FrameOf(2, 9), FrameOf(3, 0), FrameOf(-1, 6), FrameOf(-1, 8)};
  const CorrectionCameras c = FindCorrectionCameras(d);
  EXPECT_EQ(c.count, 4);  // ids 2, 7; poses x = 5, x = 6
  EXPECT_EQ(c.train, (std::vector<int>{1, 0, 1, 2, 3, 2}));
  // id 2 is a training camera wherever it stands; id 3 and an unseen pose are not.
  EXPECT_EQ(c.test, (std::vector<int>{0, -1, 3, -1}));
  EXPECT_TRUE(c.val.empty());
  EXPECT_EQ(&c.Of(Split::kTest), &c.test);
}

void MakeScene(const fs::path& root) {
  train_testing::MakeTinyHdrScene(root, 16);  // two training cameras, the last one held out
}

TrainOptions CorrectedRun(const fs::path& scene, const fs::path& run, int iterations) {
  TrainOptions o = train_testing::TinyRunOptions(scene, run, iterations, /*seed=*/5);
  o.init.num_random_points = 300;
  OptimizationOptions& opt = o.optimization;
  opt.densify_until = 40;
  opt.opacity_reset_interval = OptimizationOptions{}.opacity_reset_interval;  // the defaults
  opt.densify_grad_threshold = OptimizationOptions{}.densify_grad_threshold;
  o.hdr.method = "hdr4dgs";
  o.hdr.color_mode = ColorMode::kLogHdr;
  o.hdr.tone_mapper = ToneMapperConfig{};
  o.hdr.tone_mapper->context_window = 2;
  o.camera_correction = true;
  o.camera_correction_lr = 0.02;  // moves visibly in a few steps
  return o;
}

TEST(CameraCorrectionTraining, ResumesExactlyRecordsAndRendersPerCamera) {
  TempDir dir;
  MakeScene(dir / "scene");
  const TrainSummary whole = Train(CorrectedRun(dir / "scene", dir / "whole", 30));
  Train(CorrectedRun(dir / "scene", dir / "split", 15));
  TrainOptions rest = CorrectedRun(dir / "scene", dir / "split", 30);
  rest.resume = true;
  EXPECT_EQ(Train(rest).loss_curve, whole.loss_curve);
  const Checkpoint a = LoadCheckpoint(dir / "whole" / "checkpoint.bin");
  const Checkpoint b = LoadCheckpoint(dir / "split" / "checkpoint.bin");
  ASSERT_TRUE(a.trainer.contains("camera_correction"));
  EXPECT_EQ(a.trainer["camera_correction"], b.trainer["camera_correction"]);

  const nlohmann::json config = ReadJsonFile(dir / "whole" / "config.json");
  EXPECT_TRUE(config["camera_correction"].get<bool>());
  EXPECT_EQ(config["camera_correction_cameras"], 2);
  const nlohmann::json results = ReadJsonFile(dir / "whole" / "results.json");
  const auto gains = results["camera_log_gains"].get<std::vector<float>>();
  ASSERT_EQ(gains.size(), 6u);
  float moved = 0;
  for (float g : gains) moved = std::max(moved, std::abs(g));
  EXPECT_GT(moved, 1e-3f);

  // The held-out camera renders without gains; the same view as training camera 0 with them:
  // another LDR image, the same HDR one (the scene's radiance).
  LoadedRun run = LoadRun(dir / "whole");
  EXPECT_EQ(run.correction_cameras.count, 2);
  for (int row : run.correction_cameras.test) EXPECT_EQ(row, -1);
  const std::unique_ptr<ViewRenderer> renderer = MakeRunRenderer(run);
  const Frame& f = run.dataset.test.front();
  const auto time = static_cast<float>(f.time);
  std::vector<float> ldr0, hdr0, ldr1, hdr1;
  renderer->Render(f.camera, time, RunToneFrame(run, time, f.exposure), &ldr0, &hdr0);
  renderer->Render(f.camera, time, RunToneFrame(run, time, f.exposure, 0), &ldr1, &hdr1);
  EXPECT_EQ(hdr0, hdr1);
  EXPECT_NE(ldr0, ldr1);
  RenderRunOptions r;
  r.run = dir / "whole";
  r.out = dir / "renders";
  EXPECT_GT(RenderRun(r), 0);

  // Resuming without it is a configuration error; a checkpoint without the gains, or a dataset
  // with another camera count, is refused by name.
  TrainOptions off = CorrectedRun(dir / "scene", dir / "split", 40);
  off.resume = true;
  off.camera_correction = false;
  EXPECT_NE(ErrorOf([&] { Train(off); }).find("camera_correction"), std::string::npos);
  Checkpoint broken = a;
  broken.trainer.erase("camera_correction");
  SaveCheckpoint(dir / "whole" / "checkpoint.bin", broken);
  r.out = dir / "renders2";
  const std::string message = ErrorOf([&] { RenderRun(r); });
  EXPECT_NE(message.find("checkpoint.bin"), std::string::npos) << message;
  EXPECT_NE(message.find("camera_correction"), std::string::npos) << message;
  nlohmann::json changed = config;
  changed["camera_correction_cameras"] = 3;
  WriteJsonFile(dir / "split" / "config.json", changed);
  r.run = dir / "split";
  const std::string cameras = ErrorOf([&] { RenderRun(r); });
  EXPECT_NE(cameras.find("camera_correction_cameras"), std::string::npos) << cameras;
}

// --stop-on-val scores the val views with their cameras' gains, as the test views: with both
// splits a copy of the training frames, the two curves are the same numbers.
TEST(CameraCorrectionTraining, ValViewsAreScoredWithTheirCamerasGains) {
  TempDir dir;
  MakeScene(dir / "scene");
  for (const char* split : {"transforms_test.json", "transforms_val.json"}) {
    fs::copy_file(dir / "scene" / "transforms_train.json", dir / "scene" / split,
                  fs::copy_options::overwrite_existing);
  }
  TrainOptions o = CorrectedRun(dir / "scene", dir / "run", 40);
  o.test_every = 10;
  o.optimization.stop_window = 10;
  o.optimization.stop_tolerance = 0.9;
  o.optimization.stop_on_val = true;
  Train(o);
  const nlohmann::json results = ReadJsonFile(dir / "run" / "results.json");
  const nlohmann::json& val = results.at("val_curve");
  const nlohmann::json& test = results.at("test_curve");
  ASSERT_GE(val.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(val[i]["iteration"], test[i]["iteration"]);
    EXPECT_DOUBLE_EQ(val[i]["psnr"].get<double>(), test[i]["psnr"].get<double>()) << i;
  }
}

TEST(CameraCorrectionTraining, NeedsAToneMapper) {
  TempDir dir;
  MakeScene(dir / "scene");
  TrainOptions o = CorrectedRun(dir / "scene", dir / "run", 5);
  o.hdr = HdrTrainingOptions{};  // plain 4DGS: LDR colours, no tone mapper
  const std::string message = ErrorOf([&] { Train(o); });
  EXPECT_NE(message.find("--camera-correction"), std::string::npos) << message;
  EXPECT_NE(message.find("no tone"), std::string::npos) << message;
}

}  // namespace
}  // namespace hdr4d::method
