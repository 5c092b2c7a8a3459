#include "baselines/hexplane/hexplane_train.h"

#include <gtest/gtest.h>

#include "baselines/hexplane/hexplane_render.h"
#include "baselines/hexplane/hexplane_run.h"
#include "core/files/json_util.h"
#include "core/util/error.h"
#include "method/run/gaussian_scene.h"
#include "tests/testing.h"

namespace hdr4d::baselines::hexplane {
namespace {
namespace fs = std::filesystem;
using hdr4d::testing::ErrorOf;
using hdr4d::testing::TempDir;

// A tiny known scene (cameras on a ring of radius 4 around the origin: inside the reference's
// D-NeRF near/far 2..6 and box 1.5) and a grid small enough for a few seconds of training, with
// the upsampling and occupancy schedules scaled into the run.
void MakeScene(const fs::path& root) {
  method::GaussianSceneOptions s;
  s.size = 24;
  s.num_gaussians = 12;
  s.num_cameras = 4;
  s.num_timestamps = 3;
  method::MakeGaussianScene(s, root);
}

HexPlaneTrainOptions SmallRun(const fs::path& scene, const fs::path& run, int iterations) {
  HexPlaneTrainOptions o;
  o.data = scene;
  o.out = run;
  o.progress = false;
  o.iterations = iterations;
  o.batch_rays = 512;
  o.voxels_init = 12 * 12 * 12;
  o.voxels_final = 20 * 20 * 20;
  o.time_grid_init = 3;
  o.time_grid_final = 4;
  return o;
}

TEST(HexPlaneTrain, LearnsTheSceneAndWritesARunThatRenders) {
  TempDir dir;
  MakeScene(dir / "scene");
  const HexPlaneTrainSummary few = TrainHexPlane(SmallRun(dir / "scene", dir / "few", 2));
  const HexPlaneTrainSummary more = TrainHexPlane(SmallRun(dir / "scene", dir / "run", 150));
  EXPECT_GT(more.test_metrics["psnr"].get<double>(), few.test_metrics["psnr"].get<double>() + 2.0)
      << few.test_metrics.dump() << " -> " << more.test_metrics.dump();
  for (const char* f : {"config.json", "checkpoint.bin", "results.json"})
    EXPECT_TRUE(fs::exists(dir / "run" / f)) << f;
  const nlohmann::json results = ReadJsonFile(dir / "run" / "results.json");
  EXPECT_EQ(results["iterations"], 150);
  EXPECT_EQ(results["grid"][0], 20);  // upsampled to the final grid within the run
  ASSERT_TRUE(IsHexPlaneRun(dir / "run"));
  EXPECT_FALSE(IsHexPlaneRun(dir / "scene"));
  // The saved model renders the test views as the trained one scored them.
  const LoadedHexPlaneRun loaded = LoadHexPlaneRun(dir / "run");
  EXPECT_FALSE(loaded.model.occupancy.empty());
  const int written = RenderHexPlaneRun({.run = dir / "run", .out = dir / "renders"});
  EXPECT_EQ(written, static_cast<int>(loaded.dataset.test.size()));
}

TEST(HexPlaneTrain, BadInputsAreErrors) {
  TempDir dir;
  MakeScene(dir / "scene");
  HexPlaneTrainOptions o = SmallRun(dir / "scene", dir / "run", 1);
  o.method = "hexplane-hdr";  // needs HDR ground truth, which this scene lacks
  EXPECT_NE(ErrorOf([&] { TrainHexPlane(o); }).find("no HDR ground truth"), std::string::npos);
  o.method = "hexplane";
  o.supervision = "ldr+hdr";
  EXPECT_NE(ErrorOf([&] { TrainHexPlane(o); }).find("is neither"), std::string::npos);
  o.supervision = "auto";
  o.voxels_final = 10;  // below the initial grid
  EXPECT_NE(ErrorOf([&] { TrainHexPlane(o); }).find("voxels"), std::string::npos);
  // A checkpoint cut short is refused with its name.
  o = SmallRun(dir / "scene", dir / "run", 1);
  TrainHexPlane(o);
  fs::resize_file(dir / "run" / "checkpoint.bin", 100);
  EXPECT_NE(ErrorOf([&] { LoadHexPlaneRun(dir / "run"); }).find("checkpoint.bin"),
            std::string::npos);
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
