#include "benchmark/stress_kit.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <thread>

#include "benchmark/child_process.h"
#include "benchmark/machine.h"
#include "benchmark/scoring.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/geometry/ply.h"

namespace hdr4d::bench::stress {
namespace fs = std::filesystem;

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Exec Hdr4d(const Ctx& c, std::vector<std::string> args, const std::atomic<bool>* cancel,
           int stop_signal) {
  args.insert(args.begin(), c.hdr4d);
  static std::atomic<int> counter{0};
  const fs::path log = c.dir / fmt::format("cmd{:03d}.log", counter++);
  Exec e;
  e.r = RunChild({.argv = args, .log = log, .timeout_seconds = 600, .cancel = cancel,
                  .stop_signal = stop_signal});
  e.text = ReadText(log);
  return e;
}

bool NoCrash(const ChildResult& r) { return r.signal == 0 && (r.exit_code == 0 || r.exit_code == 1); }

// Exit code 1, exactly one "hdr4d: error:" line, naming `file`, and no sign of an abort.
bool ClearError(const Exec& e, const std::string& file) {
  int lines = 0;
  std::istringstream in(e.text);
  for (std::string line; std::getline(in, line);) lines += line.rfind("hdr4d: error:", 0) == 0;
  return e.r.exit_code == 1 && e.r.signal == 0 && lines == 1 &&
         e.r.error_line.find(file) != std::string::npos &&
         e.text.find("internal check failed") == std::string::npos &&
         e.text.find("terminate called") == std::string::npos;
}

std::string Short(const Exec& e) {
  return e.r.ok() ? "exit 0" : e.r.Describe();
}

// A small built-in scene: 24 px, 3 cameras (the last held out), 3 timestamps, LDR at the
// given exposures through the filmic response with noise.
void MakeScene(const Ctx& c, const fs::path& dir, std::vector<std::string> flags, bool synth) {
  std::vector<std::string> args = {"make-demo-scene", "--out", dir.string(), "--size", "24", "--spp", "1"};
  auto has = [&](const char* f) { return std::find(flags.begin(), flags.end(), f) != flags.end(); };
  if (!has("--timestamps")) flags.insert(flags.end(), {"--timestamps", "3"});
  if (!has("--cameras")) flags.insert(flags.end(), {"--cameras", "3"});
  args.insert(args.end(), flags.begin(), flags.end());
  const Exec e = Hdr4d(c, args);
  if (!e.r.ok()) Fail("stress: make-demo-scene failed: {}", e.r.Describe());
  if (synth) {
    const Exec s = Hdr4d(c, {"synth-ldr", "--data", dir.string(), "--crf", "filmic", "--full-well",
                             "20000", "--read-noise", "0.002", "--seed", "1"});
    if (!s.r.ok()) Fail("stress: synth-ldr failed: {}", s.r.Describe());
  }
}

std::vector<std::string> TrainArgs(const Ctx& c, const fs::path& scene, const fs::path& run,
                                   std::vector<std::string> extra) {
  std::vector<std::string> a = {"train", "--data", scene.string(), "--out", run.string(),
                                "--seed", "0"};
  // Defaults the extra flags may override.
  auto has = [&](const char* f) { return std::find(extra.begin(), extra.end(), f) != extra.end(); };
  if (!has("--iterations")) a.insert(a.end(), {"--iterations", "150"});
  if (!has("--threads")) a.insert(a.end(), {"--threads", std::to_string(c.threads)});
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

// Valid input: train, render the test split, score it. Fills "no crash" and "no NaN".
StressOutcome TrainRenderScore(const Ctx& c, const fs::path& scene, std::vector<std::string> extra) {
  StressOutcome o;
  const fs::path run = c.dir / "run";
  const Exec t = Hdr4d(c, TrainArgs(c, scene, run, extra));
  o.checks[kNoCrash] = NoCrash(t.r);
  o.checks[kNoNaN] = false;
  if (!t.r.ok()) {
    o.detail = "train: " + Short(t);
    return o;
  }
  const nlohmann::json results = ReadJsonFile(run / "results.json");
  std::vector<std::string> bad;
  for (const auto& [k, v] : results["test"].items())
    if (!v.is_number()) bad.push_back(k);
  if (!results["final_loss"].is_number()) bad.push_back("final_loss");
  const Exec r = Hdr4d(c, {"render", "--run", run.string(), "--split", "test", "--out",
                           (c.dir / "renders").string(), "--threads", std::to_string(c.threads)});
  o.checks[kNoCrash] = NoCrash(t.r) && NoCrash(r.r);
  if (!r.r.ok()) {
    o.detail = "render: " + Short(r);
    return o;
  }
  try {
    const Dataset d = LoadDataset(scene, {.image_check = ImageCheck::kNone});
    const ScoredRenders s = ScoreRenders(d, c.dir / "renders", {});
    std::map<std::string, double> mean;
    for (const FrameResult& f : s.frames)
      for (const auto& [k, v] : f.metrics) {
        if (std::isnan(v)) bad.push_back(f.frame + ":" + k);
        mean[k] += v / static_cast<double>(s.frames.size());
      }
    o.detail = fmt::format("trained {} it, {} Gaussians; test psnr {}, mu_psnr {}",
                           results.value("iterations", 0), results.value("gaussians", 0),
                           results["test"].value("psnr", nlohmann::json()).dump(),
                           results["test"].value("mu_psnr", nlohmann::json()).dump());
  } catch (const Error& e) {
    bad.push_back(std::string("scoring: ") + e.what());
  }
  o.checks[kNoNaN] = bad.empty();
  if (!bad.empty()) o.detail = "not finite: " + fmt::format("{}", fmt::join(bad, ", "));
  return o;
}

// Invalid input: `args` must fail with a clear error naming `file`.
StressOutcome ExpectError(const Ctx& c, const std::vector<std::string>& args, const std::string& file) {
  StressOutcome o;
  const Exec e = Hdr4d(c, args);
  o.checks[kNoCrash] = NoCrash(e.r);
  o.checks[kClearError] = ClearError(e, file);
  o.detail = e.r.ok() ? "exit 0: the bad input was accepted" : e.r.Describe();
  return o;
}

void ScaleRadiance(const fs::path& scene, double k) {
  for (const auto& entry : fs::directory_iterator(scene / "hdr")) {
    Image image = ReadImage(entry.path());
    for (float& v : image.values()) v = static_cast<float>(v * k);
    WriteImage(entry.path(), image, {.format = PixelFormat::kFloat});  // half cannot hold 1e6
  }
  for (const char* name : {"transforms_train.json", "transforms_test.json"}) {
    nlohmann::json j = ReadJsonFile(scene / name);
    for (nlohmann::json& f : j["frames"]) {
      nlohmann::json& e = f["exposures"];
      if (e.is_array()) {
        for (auto& x : e) x = x.get<double>() / k;
      } else {
        e = e.get<double>() / k;
      }
    }
    WriteJsonFile(scene / name, j);
  }
}

const Frame& FirstTrainFrame(const fs::path& scene) {
  static std::map<std::string, Dataset> cache;
  // Read without protecting it: the cases corrupt the scene after finding its files.
  Dataset& d = cache[scene.string()] =
      LoadDataset(scene, {.image_check = ImageCheck::kNone, .protect_inputs = false});
  return d.train.front();
}

void WritePixel(const fs::path& exr, float value) {
  Image image = ReadImage(exr, {.require_finite = false});
  image.at(image.width() / 2, image.height() / 2, 1) = value;
  WriteImage(exr, image, {.format = PixelFormat::kFloat});
}

void Truncate(const fs::path& file, double keep) {
  const std::string bytes = ReadText(file);
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size() * keep));
}

}  // namespace hdr4d::bench::stress
