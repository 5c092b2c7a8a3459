// The stress cases with degenerate inputs: near-degenerate Gaussians (coincident, collinear) and
// scenes with one timestamp, one exposure or one camera.
#include <cmath>

#include "benchmark/stress_cases.h"
#include "core/files/json_util.h"
#include "core/geometry/ply.h"

namespace hdr4d::bench::stress {
namespace fs = std::filesystem;

void AddDegenerateGaussianCases(std::vector<Case>& cases) {
  AddCase(cases, "gaussians-coincident", "near-degenerate Gaussians",
          "every initial point at the same position (zero neighbour distance)", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            PointCloud cloud;
            for (int i = 0; i < 500; ++i) {
              cloud.positions.emplace_back(0.1f, 0.2f, 0.3f);
              cloud.colors.emplace_back(0.5f, 0.5f, 0.5f);
            }
            WritePly(c.dir / "scene" / "point3d.ply", cloud);
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
  AddCase(cases, "gaussians-collinear", "near-degenerate Gaussians",
          "initial points on one line 1e-6 apart (needle-thin Gaussians)", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            PointCloud cloud;
            for (int i = 0; i < 500; ++i) {
              cloud.positions.emplace_back(1e-6f * i, 0.0f, 0.0f);
              cloud.colors.emplace_back(0.8f, 0.4f, 0.2f);
            }
            WritePly(c.dir / "scene" / "point3d.ply", cloud);
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
}

void AddDegenerateSceneCases(std::vector<Case>& cases) {
  AddCase(cases, "single-timestamp", "degenerate scene",
          "one timestamp (a static scene: no time axis)", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {"--timestamps", "1"});
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
  AddCase(cases, "single-exposure", "degenerate scene", "every LDR image at one exposure (2 s)",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {"--exposures", "2"});
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
  AddCase(cases, "single-camera", "degenerate scene",
          "one fixed camera: train and test are its views at different times", [](const Ctx& c) {
            const fs::path scene = c.dir / "scene";
            MakeScene(c, scene, {"--timestamps", "6"});
            nlohmann::json train = ReadJsonFile(scene / "transforms_train.json");
            nlohmann::json test = train;
            nlohmann::json all = train["frames"];
            train["frames"] = test["frames"] = nlohmann::json::array();
            for (const nlohmann::json& f : all) {
              if (f.value("camera_id", -1) != 0) continue;
              const int t = static_cast<int>(std::lround(f["time"].get<double>() * 5));
              (t % 3 == 1 ? test : train)["frames"].push_back(f);
            }
            WriteJsonFile(scene / "transforms_train.json", train);
            WriteJsonFile(scene / "transforms_test.json", test);
            return TrainRenderScore(c, scene, {"--supervision", "ldr+hdr"});
          });
}

}  // namespace hdr4d::bench::stress
