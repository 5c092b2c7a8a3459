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

namespace {

// One run's stages, in order: train, render, tone curves, score, then the training's numbers
// and curves gathered. Each stage fills `record` and says whether the run goes on.
class RunStages {
 public:
  enum class Step { kNext, kFailed, kCancelled };

  RunStages(const RunSpec& run,
            const PipelineOptions& options,
            const std::function<void(const std::string&)>& on_stage)
      : run_(run),
        options_(options),
        on_stage_(on_stage),
        dir_(options.runs_dir / run.id),
        train_dir_(dir_ / "train"),
        renders_(dir_ / "renders"),
        log_(dir_ / "log.txt"),
        hdr4d_(options.hdr4d.string()),
        threads_(std::to_string(options.threads)) {}

  void Start();
  Step Train();
  Step Render();
  Step ToneCurves();
  Step Score();
  void Finish();

  RunRecord record;

 private:
  // Marks the record failed with `why` and the log to read.
  Step Failed(const std::string& why);
  // A child's end: cancelled, failed (named `what`), or on to the next step.
  Step Ended(const ChildResult& child, const char* what);
  ChildResult Child(std::vector<std::string> argv);
  void Stage(const std::string& s) {
    if (on_stage_) on_stage_(s);
  }
  double Seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  const RunSpec& run_;
  const PipelineOptions& options_;
  const std::function<void(const std::string&)>& on_stage_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  const fs::path dir_, train_dir_, renders_, log_;
  const std::string hdr4d_, threads_;
  std::vector<std::string> train_, render_;  // the commands, as recorded
  double train_rss_ = 0, render_rss_ = 0;
  nlohmann::json results_, config_, timing_;  // of the training and the render
};

void RunStages::Start() {
  fs::create_directories(dir_);
  WriteJsonFile(dir_ / "spec.json",
                {{"identity", run_.identity}, {"labels", [&] {
                                                 nlohmann::json l = nlohmann::json::array();
                                                 for (const RunLabel& x : run_.labels)
                                                   l.push_back(x.ToJson());
                                                 return l;
                                               }()}});
  RunRecord& r = record;
  r.id = run_.id;
  r.source = options_.source;
  r.labels = run_.labels;
  r.code_version = CodeVersion();
  r.git_describe = GitDescribe();
  r.machine = MachineInfo();
  r.data_checksum = run_.prepared->checksum;
  r.scene_dir = run_.prepared->dir.string();
  r.run_dir = dir_.string();
  r.started_at = UtcNow();
}

RunStages::Step RunStages::Failed(const std::string& why) {
  record.status = "failed";
  record.error = fmt::format("{} (log: {})", why, log_.string());
  record.finished_at = UtcNow();
  record.wall_seconds = Seconds();
  return Step::kFailed;
}

RunStages::Step RunStages::Ended(const ChildResult& child, const char* what) {
  if (child.cancelled) return Step::kCancelled;
  if (!child.ok()) return Failed(what + (": " + child.Describe()));
  return Step::kNext;
}

// Runs one hdr4d command with what is left of the run's time limit.
ChildResult RunStages::Child(std::vector<std::string> argv) {
  const double limit = run_.resources.minutes * 60.0;
  return RunChild({.argv = std::move(argv),
                   .log = log_,
                   .timeout_seconds = std::max(1.0, limit - Seconds()),
                   .cancel = options_.cancel});
}

// 1. Training; a finished training (killed later) is not redone, a checkpointed one resumes.
RunStages::Step RunStages::Train() {
  Stage("train");
  train_ = {
      hdr4d_,      "train", "--data", run_.prepared->dir.string(), "--out", train_dir_.string(),
      "--threads", threads_};
  train_.insert(train_.end(), run_.train_args.begin(), run_.train_args.end());
  if (const std::int64_t every = CheckpointEvery(run_.budget.iterations); every > 0)
    train_.insert(train_.end(), {"--checkpoint-every", std::to_string(every)});
  const fs::path train_process = dir_ / "train_process.json";
  const bool trained = fs::exists(train_dir_ / "results.json") &&
                       fs::exists(train_dir_ / "checkpoint.bin") && fs::exists(train_process);
  if (trained) {
    train_rss_ = NumberOr(ReadJsonFile(train_process), "peak_rss_mb", 0);
  } else {
    // Results without a checkpoint (killed after the clean-up): nothing to resume from.
    if (!fs::exists(train_dir_ / "checkpoint.bin")) fs::remove_all(train_dir_);
    const bool resume = fs::exists(train_dir_ / "checkpoint.bin");
    if (resume) train_.push_back("--resume");
    const ChildResult t = Child(train_);
    if (const Step s = Ended(t, "train"); s != Step::kNext) return s;
    train_rss_ = t.peak_rss_mb;
    WriteJsonFile(train_process, {{"peak_rss_mb", t.peak_rss_mb},
                                  {"wall_seconds", t.wall_seconds},
                                  {"resumed", resume}});
  }
  results_ = ReadJsonFile(train_dir_ / "results.json");
  config_ = ReadJsonFile(train_dir_ / "config.json");
  // The trainer's warnings went to the run's log; the harness's user sees them here too.
  for (const nlohmann::json& w : results_.value("warnings", nlohmann::json::array()))
    if (w.is_string()) spdlog::warn("bench: run {}: {}", run_.id, w.get<std::string>());
  return Step::kNext;
}

// 2. Render the test split, timed.
RunStages::Step RunStages::Render() {
  Stage("render");
  fs::remove_all(renders_);
  render_ = {hdr4d_,      "render", "--run",    train_dir_.string(),
             "--split",   "test",   "--out",    renders_.string(),
             "--threads", threads_, "--timing", (dir_ / "render_timing.json").string()};
  render_.insert(render_.end(), run_.render_args.begin(), run_.render_args.end());
  const ChildResult rr = Child(render_);
  if (const Step s = Ended(rr, "render"); s != Step::kNext) return s;
  render_rss_ = rr.peak_rss_mb;
  timing_ = ReadJsonFile(dir_ / "render_timing.json");
  return Step::kNext;
}

// 3. Tone curves over time, for tone mappers that have them.
RunStages::Step RunStages::ToneCurves() {
  if (!HasPointwiseToneMapper(config_, (train_dir_ / "config.json").string())) return Step::kNext;
  const ChildResult tc = Child({hdr4d_, "tone-curves", "--run", train_dir_.string(), "--out",
                                (dir_ / "tone_curves").string(), "--times", kToneCurveTimes});
  if (const Step s = Ended(tc, "tone-curves"); s != Step::kNext) return s;
  ReadToneCurveSeries(dir_ / "tone_curves" / "tone_curves.csv", &record);
  return Step::kNext;
}

// 4. Score every test view with core's evaluation; the run's configuration goes with it.
RunStages::Step RunStages::Score() {
  Stage("score");
  try {
    const Dataset dataset = LoadDataset(run_.prepared->dir, {.image_check = ImageCheck::kNone});
    ScoringOptions so;
    if (run_.prepared->spec->region) so.region = *run_.prepared->spec->region;
    const ScoredRenders scored = ScoreRenders(dataset, renders_, so);
    record.frames = scored.frames;
    auto shown = [](std::vector<std::string> argv) {  // the binary's name, not /proc/self/exe
      if (!argv.empty() && argv[0] == SelfExecutable()) argv[0] = SelfExecutablePath().string();
      return argv;
    };
    record.config = {{"identity", run_.identity},
                     {"threads", options_.threads},
                     {"train_command", shown(train_)},
                     {"render_command", shown(render_)},
                     {"train_config", config_},
                     // What the trainer found wrong with its run (a flat tone curve), kept with it.
                     {"train_warnings", results_.value("warnings", nlohmann::json::array())},
                     {"scoring",
                      {{"region", scored.region},
                       {"region_camera", scored.region_camera},
                       {"scoring_version", kScoringVersion}}}};
  } catch (const Error& e) {
    return Failed(std::string("score: ") + e.what());
  }
  return Step::kNext;
}

// 5. The training's numbers and curves; the checkpoint goes unless asked to be kept.
void RunStages::Finish() {
  RunRecord& r = record;
  r.train_seconds = NumberOr(results_, "train_seconds", r.train_seconds);
  r.iterations = static_cast<std::int64_t>(NumberOr(results_, "iterations", -1));
  r.gaussians = static_cast<std::int64_t>(NumberOr(results_, "gaussians", -1));
  r.render_fps = NumberOr(timing_, "fps", r.render_fps);
  r.peak_rss_mb = std::max(train_rss_, render_rss_);
  if (results_.contains("curve")) {
    const nlohmann::json& c = results_["curve"];
    for (const char* name : {"loss", "train_psnr"}) {
      if (!c.contains(name) || c[name].size() != c["iteration"].size()) continue;
      for (std::size_t i = 0; i < c[name].size(); ++i) {
        if (c[name][i].is_number())
          r.series[name].emplace_back(c["iteration"][i].get<double>(), c[name][i].get<double>());
      }
    }
  }
  for (const nlohmann::json& point : results_.value("test_curve", nlohmann::json::array())) {
    for (const auto& [key, value] : point.items()) {
      if (key != "iteration" && value.is_number())
        r.series["test:" + key].emplace_back(point["iteration"].get<double>(), value.get<double>());
    }
  }
  if (!options_.keep_checkpoint) fs::remove(train_dir_ / "checkpoint.bin");
  r.finished_at = UtcNow();
  r.wall_seconds = Seconds();
}

}  // namespace

std::optional<RunRecord> ExecuteRun(const RunSpec& run,
                                    const PipelineOptions& options,
                                    const std::function<void(const std::string&)>& on_stage) {
  RunStages stages(run, options, on_stage);
  stages.Start();
  using Step = RunStages::Step;
  for (Step (RunStages::*stage)() :
       {&RunStages::Train, &RunStages::Render, &RunStages::ToneCurves, &RunStages::Score}) {
    const Step s = (stages.*stage)();
    if (s == Step::kCancelled) return std::nullopt;
    if (s == Step::kFailed) return stages.record;
  }
  stages.Finish();
  return stages.record;
}

}  // namespace hdr4d::bench
