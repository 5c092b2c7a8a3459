// The stress cases with corrupt input: NaN and Inf pixels, broken JSON, a bad key, truncated and
// missing images, an unwritable output folder, a NaN submission.
#include <fmt/format.h>

#include <fstream>
#include <limits>

#include "benchmark/stress_cases.h"
#include "core/files/json_util.h"
#include "core/util/error.h"

namespace hdr4d::bench::stress {
namespace fs = std::filesystem;

void AddCorruptInputCases(std::vector<Case>& cases) {
  AddCase(cases, "nan-pixel-hdr", "corrupt input",
          "a NaN pixel in a training view's HDR ground truth", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            const fs::path exr = *FirstTrainFrame(c.dir / "scene").hdr_path;
            WritePixel(exr, std::numeric_limits<float>::quiet_NaN());
            return ExpectError(
                c, TrainArgs(c, c.dir / "scene", c.dir / "run", {"--supervision", "ldr+hdr"}),
                exr.filename().string());
          });
  AddCase(cases, "inf-pixel-hdr", "corrupt input",
          "an +Inf pixel in a training view's HDR ground truth", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            const fs::path exr = *FirstTrainFrame(c.dir / "scene").hdr_path;
            WritePixel(exr, std::numeric_limits<float>::infinity());
            return ExpectError(
                c, TrainArgs(c, c.dir / "scene", c.dir / "run", {"--supervision", "ldr+hdr"}),
                exr.filename().string());
          });
  AddCase(cases, "broken-json", "corrupt input", "transforms_train.json cut in half",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            Truncate(c.dir / "scene" / "transforms_train.json", 0.5);
            return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}),
                               "transforms_train.json");
          });
  AddCase(cases, "bad-json-key", "corrupt input", "a frame's exposures is the string \"fast\"",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            nlohmann::json j = ReadJsonFile(c.dir / "scene" / "transforms_train.json");
            j["frames"][0]["exposures"] = "fast";
            WriteJsonFile(c.dir / "scene" / "transforms_train.json", j);
            return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}),
                               "transforms_train.json");
          });
  AddCase(cases, "truncated-png", "corrupt input", "a training LDR image cut to 60% of its bytes",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            const fs::path png = FirstTrainFrame(c.dir / "scene").image_path;
            Truncate(png, 0.6);
            return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}),
                               png.filename().string());
          });
  AddCase(cases, "missing-image", "corrupt input", "a training LDR image deleted",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            const fs::path png = FirstTrainFrame(c.dir / "scene").image_path;
            fs::remove(png);
            return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}),
                               png.filename().string());
          });
  AddCase(cases, "unwritable-output", "corrupt input", "--out below a regular file",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {});
            std::ofstream(c.dir / "a_file") << "x";
            return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "a_file" / "run", {}),
                               "a_file");
          });
}

static StressOutcome NanPixelSubmission(const Ctx& c) {
  MakeScene(c, c.dir / "scene", {});
  const fs::path run = c.dir / "run", renders = c.dir / "renders", store = c.dir / "store.db";
  const Exec t = Hdr4d(
      c, TrainArgs(c, c.dir / "scene", run, {"--iterations", "60", "--supervision", "ldr+hdr"}));
  const Exec r = Hdr4d(c, {"render", "--run", run.string(), "--out", renders.string()});
  if (!t.r.ok() || !r.r.ok()) Fail("train/render failed");
  const Exec good =
      Hdr4d(c, {"bench", "submit", "--store", store.string(), "--method", "good", "--scene",
                (c.dir / "scene").string(), "--renders", renders.string()});
  const std::string before = ReadText(store);
  fs::path exr;
  for (const auto& e : fs::directory_iterator(renders))
    if (e.path().extension() == ".exr") exr = e.path();
  WritePixel(exr, std::numeric_limits<float>::quiet_NaN());
  StressOutcome o =
      ExpectError(c,
                  {"bench", "submit", "--store", store.string(), "--method", "bad", "--scene",
                   (c.dir / "scene").string(), "--renders", renders.string()},
                  exr.filename().string());
  int runs = -1;
  try {
    runs = static_cast<int>(ResultsStore(store, false).Summaries().size());
  } catch (const Error&) {
  }
  o.checks[kNothingLost] = good.r.ok() && runs == 1;
  o.detail += fmt::format("; store holds {} run(s)", runs);
  return o;
}

void AddCorruptSubmissionCase(std::vector<Case>& cases) {
  AddCase(cases, "nan-pixel-submission", "corrupt input",
          "bench submit of renders with a NaN pixel: refused, the store unchanged",
          NanPixelSubmission);
}

}  // namespace hdr4d::bench::stress
