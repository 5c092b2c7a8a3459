// The stress cases (benchmark/stress.h lists what they cover).
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <thread>

#include "benchmark/machine.h"
#include "benchmark/scoring.h"
#include "benchmark/stress_kit.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/geometry/ply.h"
#include "method/gaussian/constants.h"
#include "method/train/checkpoint.h"

namespace hdr4d::bench::stress {
namespace fs = std::filesystem;

// Runs stored with status ok, read through a read-only connection that takes no write lock (in
// WAL mode a reader never blocks the harness's writes): the watcher of killed-harness-resumed
// polls with it. 0 while the store or its tables do not exist yet.
static int StoredOkRuns(const fs::path& store) {
  if (!fs::exists(store)) return 0;
  sqlite3* db = nullptr;
  int count = 0;
  if (sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM runs WHERE status = 'ok'", -1, &stmt,
                           nullptr) == SQLITE_OK &&
        sqlite3_step(stmt) == SQLITE_ROW) {
      count = sqlite3_column_int(stmt, 0);
    }
    sqlite3_finalize(stmt);
  }
  sqlite3_close(db);
  return count;
}

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
              if (StoredOkRuns(store) > 0) kill = true;
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

}  // namespace hdr4d::bench::stress
