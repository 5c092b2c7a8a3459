#include "benchmark/run_pipeline.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <fstream>
#include <sstream>

#include "baselines/tone_mapper_kinds.h"
#include "benchmark/child_process.h"
#include "benchmark/machine.h"
#include "benchmark/scoring.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/files/json_util.h"
#include "method/tonemap/tone_mapper.h"
#include "method/tonemap/tone_mapper_registry.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

double NumberOr(const nlohmann::json& j, const char* key, double fallback) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

// Whether the trained run has a tone mapper with one curve per channel (not Durand's local
// operator), i.e. whether `hdr4d tone-curves` applies.
bool HasPointwiseToneMapper(const nlohmann::json& config, const std::string& source) {
  if (!config.contains("tone_mapper")) return false;
  baselines::RegisterToneMappers();
  const auto mapper = method::MakeToneMapper(
      method::ToneMapperConfig::FromJson(config["tone_mapper"], source));
  return mapper->pointwise();
}

// Training lasts at most 5 checkpoints' worth of lost work when a run is killed.
std::int64_t CheckpointEvery(std::int64_t iterations) {
  return iterations >= 2000 ? iterations / 5 : 0;
}

}  // namespace

void ReadToneCurveSeries(const fs::path& csv, RunRecord* record) {
  std::ifstream in(csv);
  if (!in) Fail("{}: cannot read the tone curves", csv.string());
  std::string header;
  std::getline(in, header);
  std::vector<std::string> names;
  std::stringstream hs(header);
  for (std::string col; std::getline(hs, col, ',');) names.push_back(col);
  // Columns: x, then <channel>_t<time> for every time and channel.
  std::vector<std::string> series_names;
  for (std::size_t c = 1; c < names.size(); ++c) {
    const std::string& n = names[c];
    const auto t = n.find("_t");
    if (t == std::string::npos) Fail("{}: unexpected column '{}'", csv.string(), n);
    series_names.push_back(fmt::format("tone:{}:{}", n.substr(t + 2), n.substr(0, t)));
  }
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    std::stringstream ls(line);
    std::string cell;
    std::getline(ls, cell, ',');
    const double x = std::stod(cell);
    for (const std::string& name : series_names) {
      if (!std::getline(ls, cell, ',')) Fail("{}: short row", csv.string());
      record->series[name].emplace_back(x, std::stod(cell));
    }
  }
}

std::optional<RunRecord> ExecuteRun(const RunSpec& run, const PipelineOptions& options,
                                    const std::function<void(const std::string&)>& on_stage) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path dir = options.runs_dir / run.id;
  const fs::path train_dir = dir / "train", renders = dir / "renders";
  const fs::path log = dir / "log.txt";
  fs::create_directories(dir);
  WriteJsonFile(dir / "spec.json", {{"identity", run.identity},
                                    {"labels", [&] {
                                       nlohmann::json l = nlohmann::json::array();
                                       for (const RunLabel& x : run.labels) l.push_back(x.ToJson());
                                       return l;
                                     }()}});
  RunRecord r;
  r.id = run.id;
  r.source = options.source;
  r.labels = run.labels;
  r.code_version = CodeVersion();
  r.git_describe = GitDescribe();
  r.machine = MachineInfo();
  r.data_checksum = run.prepared->checksum;
  r.scene_dir = run.prepared->dir.string();
  r.run_dir = dir.string();
  r.started_at = UtcNow();
  const double limit = run.resources.minutes * 60.0;
  auto remaining = [&] {
    return std::max(1.0, limit - std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                                                start)
                                     .count());
  };
  auto stage = [&](const std::string& s) {
    if (on_stage) on_stage(s);
  };
  auto fail = [&](const std::string& why) {
    r.status = "failed";
    r.error = fmt::format("{} (log: {})", why, log.string());
    r.finished_at = UtcNow();
    r.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
  };
  const std::string hdr4d = options.hdr4d.string(), threads = std::to_string(options.threads);

  // 1. Training; a finished training (killed later) is not redone, a checkpointed one resumes.
  stage("train");
  std::vector<std::string> train = {hdr4d, "train", "--data", run.prepared->dir.string(),
                                    "--out", train_dir.string(), "--threads", threads};
  train.insert(train.end(), run.train_args.begin(), run.train_args.end());
  if (const std::int64_t every = CheckpointEvery(run.budget.iterations); every > 0)
    train.insert(train.end(), {"--checkpoint-every", std::to_string(every)});
  const fs::path train_process = dir / "train_process.json";
  double train_rss = 0;
  const bool trained = fs::exists(train_dir / "results.json") &&
                       fs::exists(train_dir / "checkpoint.bin") && fs::exists(train_process);
  if (trained) {
    train_rss = NumberOr(ReadJsonFile(train_process), "peak_rss_mb", 0);
  } else {
    // Results without a checkpoint (killed after the clean-up): nothing to resume from.
    if (!fs::exists(train_dir / "checkpoint.bin")) fs::remove_all(train_dir);
    const bool resume = fs::exists(train_dir / "checkpoint.bin");
    if (resume) train.push_back("--resume");
    ChildResult t = RunChild({.argv = train,
                              .log = log,
                              .timeout_seconds = remaining(),
                              .cancel = options.cancel});
    if (t.cancelled) return std::nullopt;
    if (!t.ok()) return fail("train: " + t.Describe());
    train_rss = t.peak_rss_mb;
    WriteJsonFile(train_process, {{"peak_rss_mb", t.peak_rss_mb},
                                  {"wall_seconds", t.wall_seconds},
                                  {"resumed", resume}});
  }
  const nlohmann::json results = ReadJsonFile(train_dir / "results.json");
  const nlohmann::json config = ReadJsonFile(train_dir / "config.json");
  // The trainer's warnings went to the run's log; the harness's user sees them here too.
  for (const nlohmann::json& w : results.value("warnings", nlohmann::json::array()))
    if (w.is_string()) spdlog::warn("bench: run {}: {}", run.id, w.get<std::string>());

  // 2. Render the test split, timed.
  stage("render");
  fs::remove_all(renders);
  std::vector<std::string> render = {hdr4d,   "render",  "--run",   train_dir.string(),
                                     "--split", "test",  "--out",   renders.string(),
                                     "--threads", threads, "--timing", (dir / "render_timing.json").string()};
  render.insert(render.end(), run.render_args.begin(), run.render_args.end());
  ChildResult rr = RunChild({.argv = render, .log = log, .timeout_seconds = remaining(),
                             .cancel = options.cancel});
  if (rr.cancelled) return std::nullopt;
  if (!rr.ok()) return fail("render: " + rr.Describe());
  const nlohmann::json timing = ReadJsonFile(dir / "render_timing.json");

  // 3. Tone curves over time, for tone mappers that have them.
  if (HasPointwiseToneMapper(config, (train_dir / "config.json").string())) {
    ChildResult tc = RunChild({.argv = {hdr4d, "tone-curves", "--run", train_dir.string(), "--out",
                                        (dir / "tone_curves").string(), "--times",
                                        kToneCurveTimes},
                               .log = log,
                               .timeout_seconds = remaining(),
                               .cancel = options.cancel});
    if (tc.cancelled) return std::nullopt;
    if (!tc.ok()) return fail("tone-curves: " + tc.Describe());
    ReadToneCurveSeries(dir / "tone_curves" / "tone_curves.csv", &r);
  }

  // 4. Score every test view with core's evaluation.
  stage("score");
  try {
    const Dataset dataset =
        LoadDataset(run.prepared->dir, {.image_check = ImageCheck::kNone});
    ScoringOptions so;
    if (run.prepared->spec->region) so.region = *run.prepared->spec->region;
    const ScoredRenders scored = ScoreRenders(dataset, renders, so);
    r.frames = scored.frames;
    auto shown = [](std::vector<std::string> argv) {  // the binary's name, not /proc/self/exe
      if (!argv.empty() && argv[0] == SelfExecutable()) argv[0] = SelfExecutablePath().string();
      return argv;
    };
    r.config = {{"identity", run.identity},
                {"threads", options.threads},
                {"train_command", shown(train)},
                {"render_command", shown(render)},
                {"train_config", config},
                // What the trainer found wrong with its run (a flat tone curve), kept with it.
                {"train_warnings", results.value("warnings", nlohmann::json::array())},
                {"scoring",
                 {{"region", scored.region},
                  {"region_camera", scored.region_camera},
                  {"scoring_version", kScoringVersion}}}};
  } catch (const Error& e) {
    return fail(std::string("score: ") + e.what());
  }

  r.train_seconds = NumberOr(results, "train_seconds", r.train_seconds);
  r.iterations = static_cast<std::int64_t>(NumberOr(results, "iterations", -1));
  r.gaussians = static_cast<std::int64_t>(NumberOr(results, "gaussians", -1));
  r.render_fps = NumberOr(timing, "fps", r.render_fps);
  r.peak_rss_mb = std::max(train_rss, rr.peak_rss_mb);
  if (results.contains("curve")) {
    const nlohmann::json& c = results["curve"];
    for (const char* name : {"loss", "train_psnr"}) {
      if (!c.contains(name) || c[name].size() != c["iteration"].size()) continue;
      for (std::size_t i = 0; i < c[name].size(); ++i) {
        if (c[name][i].is_number())
          r.series[name].emplace_back(c["iteration"][i].get<double>(), c[name][i].get<double>());
      }
    }
  }
  for (const nlohmann::json& point : results.value("test_curve", nlohmann::json::array())) {
    for (const auto& [key, value] : point.items()) {
      if (key != "iteration" && value.is_number())
        r.series["test:" + key].emplace_back(point["iteration"].get<double>(), value.get<double>());
    }
  }
  if (!options.keep_checkpoint) fs::remove(train_dir / "checkpoint.bin");
  r.finished_at = UtcNow();
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace hdr4d::bench
