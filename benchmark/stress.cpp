#include "benchmark/stress.h"

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
#include "core/dataset.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/ply.h"
#include "method/checkpoint.h"
#include "method/constants.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

constexpr const char* kNoCrash = "no crash";
constexpr const char* kNoNaN = "no NaN";
constexpr const char* kClearError = "clear error";
constexpr const char* kNothingLost = "nothing lost";

struct Ctx {
  fs::path dir;  // this case's folder
  std::string hdr4d;
  int threads = 0;
};

struct Exec {
  ChildResult r;
  std::string text;  // what the command printed
};

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Exec Hdr4d(const Ctx& c, std::vector<std::string> args, const std::atomic<bool>* cancel = nullptr,
           int stop_signal = 15) {
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
void MakeScene(const Ctx& c, const fs::path& dir, std::vector<std::string> flags, bool synth = true) {
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
  Dataset& d = cache[scene.string()] = LoadDataset(scene, {.image_check = ImageCheck::kNone});
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

using CaseFn = std::function<StressOutcome(const Ctx&)>;
struct Case {
  StressCaseInfo info;
  CaseFn run;
};

std::vector<Case> Cases() {
  std::vector<Case> cases;
  auto add = [&](const char* name, const char* category, const char* what, CaseFn fn) {
    cases.push_back({{name, category, what}, std::move(fn)});
  };

  add("exposure-bracket-1e-4-to-1e3", "extreme exposure",
      "LDR at 1e-4, 1 and 1e3 s (black to white); HDR-4DGS from LDR only", [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {"--exposures", "0.0001,1,1000"});
        return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
      });
  add("exposure-1e-4-only", "extreme exposure", "every LDR image at 1e-4 s (nearly black)",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {"--exposures", "0.0001"});
        return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
      });
  add("exposure-1e3-only", "extreme exposure", "every LDR image at 1e3 s (nearly white)",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {"--exposures", "1000"});
        return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
      });
  // A converged model sits at the scene's radiance scale; 150 iterations do not get there (the
  // log-HDR colours start near radiance 1, see the detail line), so the trained model's log
  // radiance is shifted by log(k) before rendering: renders at 1e-6 and 1e6, scored against
  // ground truth at that scale.
  auto radiance_case = [](double k) {
    return [k](const Ctx& c) {
      const fs::path scene = c.dir / "scene";
      MakeScene(c, c.dir / "unit", {});
      MakeScene(c, scene, {}, false);
      ScaleRadiance(scene, k);
      const Exec s = Hdr4d(c, {"synth-ldr", "--data", scene.string(), "--crf", "filmic",
                               "--full-well", "20000", "--read-noise", "0.002", "--seed", "1"});
      if (!s.r.ok()) Fail("synth-ldr: {}", s.r.Describe());
      // The same training at unit scale, for the detail line.
      const Exec unit = Hdr4d(c, TrainArgs(c, c.dir / "unit", c.dir / "unit_run", {"--supervision", "ldr+hdr"}));
      const Exec t = Hdr4d(c, TrainArgs(c, scene, c.dir / "trained", {"--supervision", "ldr+hdr"}));
      StressOutcome o;
      o.checks[kNoCrash] = NoCrash(t.r);
      o.checks[kNoNaN] = false;
      if (!t.r.ok() || !unit.r.ok()) {
        o.detail = "train: " + Short(t);
        return o;
      }
      const double psnr = ReadJsonFile(c.dir / "trained" / "results.json")["test"].value("psnr", NAN);
      const double unit_psnr = ReadJsonFile(c.dir / "unit_run" / "results.json")["test"].value("psnr", NAN);
      method::Checkpoint ck = method::LoadCheckpoint(c.dir / "trained" / "checkpoint.bin");
      for (float& v : ck.model.color_dc) v += static_cast<float>(std::log(k) / method::kShC0);
      method::SaveCheckpoint(c.dir / "trained" / "checkpoint.bin", ck);
      const Exec r = Hdr4d(c, {"render", "--run", (c.dir / "trained").string(), "--split", "test",
                               "--out", (c.dir / "renders").string()});
      o.checks[kNoCrash] = NoCrash(t.r) && NoCrash(r.r);
      if (!r.r.ok()) {
        o.detail = "render: " + Short(r);
        return o;
      }
      double max = 0;
      std::string bad;
      try {
        for (const auto& e : fs::directory_iterator(c.dir / "renders"))
          if (e.path().extension() == ".exr") max = std::max<double>(max, ReadImage(e.path()).MaxValue());
        const ScoredRenders sc = ScoreRenders(LoadDataset(scene, {.image_check = ImageCheck::kNone}),
                                              c.dir / "renders", {});
        for (const FrameResult& f : sc.frames)
          for (const auto& [key, v] : f.metrics)
            if (std::isnan(v)) bad = f.frame + ":" + key;
      } catch (const Error& e) {
        bad = e.what();
      }
      o.checks[kNoNaN] = bad.empty();
      o.detail = bad.empty()
                     ? fmt::format("HDR renders up to {:.3g}, all scores finite. Quality, not a "
                                   "numerical failure: LDR PSNR {:.1f} dB after 150 iterations "
                                   "against {:.1f} dB at unit scale, because the log-HDR colours "
                                   "start near radiance 1 and the colour learning rate moves them "
                                   "slowly toward log({:g})",
                                   max, psnr, unit_psnr, k)
                     : "not finite: " + bad;
      return o;
    };
  };
  add("radiance-1e-6", "extreme radiance",
      "HDR ground truth scaled by 1e-6 (exposures by 1e6), LDR+HDR supervision, renders at 1e-6",
      radiance_case(1e-6));
  add("radiance-1e6", "extreme radiance",
      "HDR ground truth scaled by 1e6 (exposures by 1e-6), LDR+HDR supervision, renders at 1e6",
      radiance_case(1e6));
  add("gaussians-coincident", "near-degenerate Gaussians",
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
  add("gaussians-collinear", "near-degenerate Gaussians",
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
  add("single-timestamp", "degenerate scene", "one timestamp (a static scene: no time axis)",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {"--timestamps", "1"});
        return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
      });
  add("single-exposure", "degenerate scene", "every LDR image at one exposure (2 s)",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {"--exposures", "2"});
        return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
      });
  add("single-camera", "degenerate scene",
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
  add("nan-pixel-hdr", "corrupt input", "a NaN pixel in a training view's HDR ground truth",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {});
        const fs::path exr = *FirstTrainFrame(c.dir / "scene").hdr_path;
        WritePixel(exr, std::numeric_limits<float>::quiet_NaN());
        return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {"--supervision", "ldr+hdr"}),
                           exr.filename().string());
      });
  add("inf-pixel-hdr", "corrupt input", "an +Inf pixel in a training view's HDR ground truth",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {});
        const fs::path exr = *FirstTrainFrame(c.dir / "scene").hdr_path;
        WritePixel(exr, std::numeric_limits<float>::infinity());
        return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {"--supervision", "ldr+hdr"}),
                           exr.filename().string());
      });
  add("broken-json", "corrupt input", "transforms_train.json cut in half", [](const Ctx& c) {
    MakeScene(c, c.dir / "scene", {});
    Truncate(c.dir / "scene" / "transforms_train.json", 0.5);
    return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}), "transforms_train.json");
  });
  add("bad-json-key", "corrupt input", "a frame's exposures is the string \"fast\"", [](const Ctx& c) {
    MakeScene(c, c.dir / "scene", {});
    nlohmann::json j = ReadJsonFile(c.dir / "scene" / "transforms_train.json");
    j["frames"][0]["exposures"] = "fast";
    WriteJsonFile(c.dir / "scene" / "transforms_train.json", j);
    return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}), "transforms_train.json");
  });
  add("truncated-png", "corrupt input", "a training LDR image cut to 60% of its bytes",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {});
        const fs::path png = FirstTrainFrame(c.dir / "scene").image_path;
        Truncate(png, 0.6);
        return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}), png.filename().string());
      });
  add("missing-image", "corrupt input", "a training LDR image deleted", [](const Ctx& c) {
    MakeScene(c, c.dir / "scene", {});
    const fs::path png = FirstTrainFrame(c.dir / "scene").image_path;
    fs::remove(png);
    return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "run", {}), png.filename().string());
  });
  add("unwritable-output", "corrupt input", "--out below a regular file", [](const Ctx& c) {
    MakeScene(c, c.dir / "scene", {});
    std::ofstream(c.dir / "a_file") << "x";
    return ExpectError(c, TrainArgs(c, c.dir / "scene", c.dir / "a_file" / "run", {}), "a_file");
  });
  add("corrupt-checkpoint", "killed or corrupt state",
      "bytes flipped inside checkpoint.bin, then a truncated one: render and resume must refuse",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {});
        const fs::path run = c.dir / "run";
        const Exec t = Hdr4d(c, TrainArgs(c, c.dir / "scene", run, {"--iterations", "60"}));
        if (!t.r.ok()) Fail("train: {}", t.r.Describe());
        const std::string results = ReadText(run / "results.json"), config = ReadText(run / "config.json");
        const fs::path ckpt = run / "checkpoint.bin";
        std::string bytes = ReadText(ckpt);
        for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i) bytes[i] = static_cast<char>(~bytes[i]);
        std::ofstream(ckpt, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        const Exec r = Hdr4d(c, {"render", "--run", run.string(), "--out", (c.dir / "renders").string()});
        Truncate(ckpt, 0.5);
        const Exec resume = Hdr4d(c, TrainArgs(c, c.dir / "scene", run, {"--iterations", "120", "--resume"}));
        StressOutcome o;
        o.checks[kNoCrash] = NoCrash(r.r) && NoCrash(resume.r);
        o.checks[kClearError] = ClearError(r, "checkpoint.bin") && ClearError(resume, "checkpoint.bin");
        o.checks[kNothingLost] = ReadText(run / "results.json") == results && ReadText(run / "config.json") == config;
        o.detail = fmt::format("flipped bytes, render: {}; truncated, resume: {}", Short(r), Short(resume));
        return o;
      });
  add("killed-training-resumed", "killed or corrupt state",
      "training killed (SIGKILL) after a checkpoint, then --resume: must equal an uninterrupted run",
      [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {});
        const std::vector<std::string> extra = {"--iterations", "300", "--checkpoint-every", "50",
                                                "--threads", "1"};
        const Exec whole = Hdr4d(c, TrainArgs(c, c.dir / "scene", c.dir / "whole", extra));
        if (!whole.r.ok()) Fail("train: {}", whole.r.Describe());
        std::atomic<bool> kill{false};
        std::thread watcher([&] {
          // Kill as soon as the first checkpoint is there (training is then mid-way).
          for (int i = 0; i < 6000 && !fs::exists(c.dir / "killed" / "checkpoint.bin"); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
          kill = true;
        });
        const Exec killed = Hdr4d(c, TrainArgs(c, c.dir / "scene", c.dir / "killed", extra), &kill, 9);
        watcher.join();
        std::vector<std::string> resume_args = extra;
        resume_args.push_back("--resume");
        const Exec resumed = Hdr4d(c, TrainArgs(c, c.dir / "scene", c.dir / "killed", resume_args));
        StressOutcome o;
        o.checks[kNoCrash] = NoCrash(resumed.r);
        bool same = false;
        if (resumed.r.ok()) {
          const nlohmann::json a = ReadJsonFile(c.dir / "whole" / "results.json");
          const nlohmann::json b = ReadJsonFile(c.dir / "killed" / "results.json");
          same = a["curve"] == b["curve"] && a["test"] == b["test"] && a["gaussians"] == b["gaussians"];
        }
        o.checks[kNothingLost] = killed.r.signal == 9 && same;
        o.detail = fmt::format("killed run: {}; resumed: {}; resumed == uninterrupted: {}",
                               killed.r.Describe(), Short(resumed), same ? "yes" : "no");
        return o;
      });
  add("killed-harness-resumed", "killed or corrupt state",
      "bench run killed (SIGKILL) after its first stored run, then run again", [](const Ctx& c) {
        const fs::path suite = c.dir / "suite.json", store = c.dir / "store.db";
        WriteJsonFile(suite, {{"name", "stress-kill"},
                              {"scenes", {{{"name", "tiny"},
                                           {"builtin", {{"scene", "demo"},
                                                        {"flags", {{"size", 24}, {"timestamps", 3}, {"cameras", 3}, {"spp", 1}}},
                                                        {"synth", {{"crf", "filmic"}, {"seed", 1}}}}}}}},
                              {"methods", {{{"name", "hdr4dgs"}, {"train", {{"method", "hdr4dgs"}}}},
                                           {{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}}}},
                              {"seeds", {0, 1}},
                              {"budgets", {{{"iterations", 100}}}}});
        const std::vector<std::string> args = {"bench", "run", suite.string(), "--store", store.string(),
                                               "--cache", (c.dir / "cache").string(), "--jobs", "2"};
        std::atomic<bool> kill{false};
        std::thread watcher([&] {
          for (int i = 0; i < 12000 && !kill; ++i) {
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
            try {
              if (fs::exists(store) && !ResultsStore(store, false).RunIds("ok").empty()) kill = true;
            } catch (const Error&) {
            }
          }
          kill = true;
        });
        const Exec first = Hdr4d(c, args, &kill, 9);
        watcher.join();
        StressOutcome o;
        std::map<std::string, std::string> finished_before;
        bool intact = true;
        {
          ResultsStore s(store, false);
          for (const RunSummary& r : s.Summaries()) {
            finished_before[r.run_id] = s.Record(r.run_id).finished_at;
            intact &= r.status == "ok" && !s.Frames(r.run_id).empty();
          }
        }
        const Exec second = Hdr4d(c, args);
        bool kept = second.r.ok();
        int total = 0;
        {
          ResultsStore s(store, false);
          total = static_cast<int>(s.RunIds("ok").size());
          for (const auto& [id, at] : finished_before) kept &= s.HasRun(id) && s.Record(id).finished_at == at;
        }
        o.checks[kNoCrash] = NoCrash(second.r);
        o.checks[kNothingLost] = first.r.signal == 9 && intact && kept && total == 4;
        o.detail = fmt::format("killed with {} of 4 runs stored (all complete: {}); second run: {}, "
                               "{} runs stored, the earlier ones kept: {}",
                               finished_before.size(), intact ? "yes" : "no", Short(second), total,
                               kept ? "yes" : "no");
        return o;
      });
  add("nan-pixel-submission", "corrupt input",
      "bench submit of renders with a NaN pixel: refused, the store unchanged", [](const Ctx& c) {
        MakeScene(c, c.dir / "scene", {});
        const fs::path run = c.dir / "run", renders = c.dir / "renders", store = c.dir / "store.db";
        const Exec t = Hdr4d(c, TrainArgs(c, c.dir / "scene", run, {"--iterations", "60", "--supervision", "ldr+hdr"}));
        const Exec r = Hdr4d(c, {"render", "--run", run.string(), "--out", renders.string()});
        if (!t.r.ok() || !r.r.ok()) Fail("train/render failed");
        const Exec good = Hdr4d(c, {"bench", "submit", "--store", store.string(), "--method", "good",
                                    "--scene", (c.dir / "scene").string(), "--renders", renders.string()});
        const std::string before = ReadText(store);
        fs::path exr;
        for (const auto& e : fs::directory_iterator(renders))
          if (e.path().extension() == ".exr") exr = e.path();
        WritePixel(exr, std::numeric_limits<float>::quiet_NaN());
        StressOutcome o = ExpectError(c, {"bench", "submit", "--store", store.string(), "--method", "bad",
                                          "--scene", (c.dir / "scene").string(), "--renders", renders.string()},
                                      exr.filename().string());
        int runs = -1;
        try {
          runs = static_cast<int>(ResultsStore(store, false).Summaries().size());
        } catch (const Error&) {
        }
        o.checks[kNothingLost] = good.r.ok() && runs == 1;
        o.detail += fmt::format("; store holds {} run(s)", runs);
        return o;
      });
  return cases;
}

}  // namespace

std::vector<StressCaseInfo> StressCaseList() {
  std::vector<StressCaseInfo> list;
  for (const Case& c : Cases()) list.push_back(c.info);
  return list;
}

std::vector<StressOutcome> RunStress(const StressOptions& options) {
  if (options.work.empty()) Fail("bench stress: --out is required");
  const std::vector<Case> cases = Cases();
  for (const std::string& name : options.cases) {
    if (std::none_of(cases.begin(), cases.end(), [&](const Case& c) { return c.info.name == name; }))
      Fail("bench stress: no case '{}' (bench stress --list shows them)", name);
  }
  std::optional<ResultsStore> store;
  if (!options.store.empty()) store.emplace(options.store);
  std::vector<StressOutcome> out;
  for (const Case& c : cases) {
    if (!options.cases.empty() &&
        std::find(options.cases.begin(), options.cases.end(), c.info.name) == options.cases.end())
      continue;
    Ctx ctx{options.work / c.info.name, SelfExecutable().string(), options.threads};
    fs::remove_all(ctx.dir);
    fs::create_directories(ctx.dir);
    const auto start = std::chrono::steady_clock::now();
    StressOutcome o;
    try {
      o = c.run(ctx);
    } catch (const std::exception& e) {
      // The case could not even set itself up: that is a failure of the case, reported as such.
      o.checks[kNoCrash] = nullptr;
      o.detail = std::string("setting up the case failed: ") + e.what();
      o.outcome = "failed";
    }
    o.name = c.info.name;
    o.category = c.info.category;
    o.description = c.info.description;
    bool held = o.outcome != "failed";
    for (const auto& [k, v] : o.checks.items()) held &= v.is_null() || v.get<bool>();
    o.outcome = held ? "held" : "failed";
    o.code_version = CodeVersion();
    o.finished_at = UtcNow();
    fmt::print("stress: {:<30} {:<6} {:.1f} s  {}\n", o.name, o.outcome,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), o.detail);
    std::fflush(stdout);
    if (store) store->WriteStress(o);
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace hdr4d::bench
