#include "benchmark/slurm.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>

#include "benchmark/child_process.h"
#include "benchmark/kept_records.h"
#include "benchmark/machine.h"
#include "benchmark/results_store.h"
#include "benchmark/run_pipeline.h"
#include "benchmark/run_plan.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

std::string SlurmTime(double minutes) {
  const long total = static_cast<long>(std::ceil(minutes));
  return fmt::format("{}:{:02d}:00", total / 60, total % 60);
}

nlohmann::json SpecJson(const RunSpec& r) {
  nlohmann::json labels = nlohmann::json::array();
  for (const RunLabel& l : r.labels) labels.push_back(l.ToJson());
  return {{"id", r.id},
          {"labels", labels},
          {"method", r.method},
          {"scene", r.scene},
          {"scene_dir", r.prepared->dir.string()},
          {"data_checksum", r.prepared->checksum},
          {"region", r.prepared->spec->region ? nlohmann::json(*r.prepared->spec->region)
                                              : nlohmann::json(nullptr)},
          {"budget", {{"iterations", r.budget.iterations}, {"seconds", r.budget.seconds}}},
          {"train_args", r.train_args},
          {"render_args", r.render_args},
          {"identity", r.identity},
          {"resources", r.resources.ToJson()}};
}

// Every value that reaches a generated script is checked before anything is planned: a newline
// in the suite name, --partition or --account ended up as a command of its own in the sbatch
// script (issue 51, case 7).
void RequireNoControlCharacters(const std::string& what, const std::string& value) {
  for (const unsigned char c : value) {
    if (c < 0x20 || c == 0x7f) {
      Fail("bench slurm: {} contains a control character (0x{:02x}); it would reach the "
           "generated scripts", what, static_cast<int>(c));
    }
  }
}

// Slurm's partition and account names: letters, digits and . _ - (a partition list adds ,).
void RequireSlurmName(const std::string& what, const std::string& value) {
  RequireNoControlCharacters(what, value);
  for (const char c : value) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-' &&
        c != ',') {
      Fail("bench slurm: {} '{}' has the character '{}'; Slurm names are letters, digits and . _ - "
           "(a partition list separated by ,)", what, value, c);
    }
  }
}

// The suite name as a job name: what Slurm shows, kept to characters no parser splits on.
std::string JobNamePart(const std::string& name) {
  std::string out = name;
  for (char& c : out) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '_';
  }
  return out;
}

// A path on an #SBATCH line: sbatch reads it up to white space unless it is in double quotes.
std::string SbatchPath(const std::string& path) {
  if (path.find('"') != std::string::npos)
    Fail("bench slurm: {}: a '\"' in the output path cannot be written on an #SBATCH line", path);
  const bool plain = std::none_of(path.begin(), path.end(), [](char c) { return c == ' ' || c == '\t'; });
  return plain ? path : "\"" + path + "\"";
}

}  // namespace

SlurmPlan WriteSlurmJobs(const Suite& suite, const SlurmOptions& o) {
  if (o.out.empty()) Fail("bench slurm: --out is required");
  if (o.max_parallel < 0) Fail("bench slurm: --max-parallel must be >= 0");
  const fs::path dir = fs::absolute(o.out);
  RequireNoControlCharacters("the suite name", suite.name);
  RequireNoControlCharacters("--out", dir.string());
  RequireSlurmName("--partition", o.partition);
  RequireSlurmName("--account", o.account);
  const fs::path cache = o.cache_dir.empty() ? DefaultCacheDir() : fs::absolute(o.cache_dir);
  const std::vector<PreparedScene> scenes = PrepareScenes(suite, cache, true);
  const std::vector<RunSpec> runs = PlanRuns(suite, scenes, CodeVersion());
  std::set<std::string> stored;
  if (!o.store.empty() && fs::exists(o.store)) stored = ResultsStore(o.store, false).RunIds("ok");

  // Group by resource request: a job array asks for one.
  std::map<std::string, std::vector<const RunSpec*>> groups;
  SlurmPlan plan;
  for (const RunSpec& r : runs) {
    if (stored.count(r.id)) {
      ++plan.skipped;
      continue;
    }
    groups[r.resources.ToJson().dump()].push_back(&r);
  }
  fs::create_directories(dir / "results");
  fs::create_directories(dir / "logs");
  const std::string hdr4d = SelfExecutablePath().string();
  nlohmann::json arrays = nlohmann::json::array();
  std::string submit = "#!/bin/bash\n# Submits every job array of this plan (hdr4d bench slurm).\nset -euo pipefail\ncd \"$(dirname \"$0\")\"\n";
  int k = 0;
  for (const auto& [key, list] : groups) {
    const Resources& res = list.front()->resources;
    nlohmann::json tasks = nlohmann::json::array();
    for (const RunSpec* r : list) tasks.push_back(SpecJson(*r));
    arrays.push_back({{"resources", res.ToJson()}, {"tasks", tasks}});
    std::string script = "#!/bin/bash\n";
    script += fmt::format("#SBATCH --job-name=hdr4d-{}-{}\n", JobNamePart(suite.name), k);
    script += fmt::format("#SBATCH --array=0-{}{}\n", list.size() - 1,
                          o.max_parallel > 0 ? fmt::format("%{}", o.max_parallel) : "");
    script += "#SBATCH --ntasks=1\n";
    script += fmt::format("#SBATCH --cpus-per-task={}\n", res.cpus);
    script += fmt::format("#SBATCH --mem={}M\n", static_cast<long>(std::ceil(res.memory_gb * 1024)));
    script += fmt::format("#SBATCH --time={}\n", SlurmTime(res.minutes));
    script += fmt::format("#SBATCH --output={}\n", SbatchPath(dir.string() + "/logs/%A_%a.out"));
    if (!o.partition.empty()) script += fmt::format("#SBATCH --partition={}\n", o.partition);
    if (!o.account.empty()) script += fmt::format("#SBATCH --account={}\n", o.account);
    script += fmt::format(
        "# {} runs of suite '{}' needing {} cpus, {} GB, {} min each; task i runs the i-th of\n"
        "# arrays[{}].tasks in plan.json and writes results/<run id>.json.\n",
        list.size(), suite.name, res.cpus, res.memory_gb, res.minutes, k);
    script += "set -euo pipefail\n";
    script += "if [ -z \"${SLURM_ARRAY_TASK_ID:-}\" ]; then echo 'hdr4d: error: not a Slurm array task (SLURM_ARRAY_TASK_ID unset)' >&2; exit 1; fi\n";
    script += fmt::format("exec {} bench task {} --array {} --index \"$SLURM_ARRAY_TASK_ID\"\n",
                          ShellQuote(hdr4d), ShellQuote(dir.string()), k);
    const fs::path path = dir / fmt::format("array_{}.sbatch", k);
    WriteTextFileAtomic(path, script);
    fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
    submit += fmt::format("sbatch --parsable {}\n", path.filename().string());
    ++k;
  }
  WriteJsonFile(dir / "plan.json", {{"suite", suite.name},
                                    {"suite_file", suite.file.string()},
                                    {"code_version", CodeVersion()},
                                    {"hdr4d", hdr4d},
                                    {"arrays", arrays}});
  WriteTextFileAtomic(dir / "submit.sh", submit);
  fs::permissions(dir / "submit.sh", fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
  plan.arrays = k;
  plan.runs = static_cast<int>(runs.size()) - plan.skipped;
  return plan;
}

bool RunSlurmTask(const fs::path& dir, int array, int index) {
  const nlohmann::json plan = ReadJsonFile(dir / "plan.json");
  const std::string where = (dir / "plan.json").string();
  if (plan.value("code_version", "") != CodeVersion()) {
    Fail("{}: planned with code version {}, this hdr4d is {}; run `hdr4d bench slurm` again",
         where, plan.value("code_version", "?"), CodeVersion());
  }
  if (array < 0 || array >= static_cast<int>(plan["arrays"].size()))
    Fail("{}: no array {}", where, array);
  const nlohmann::json& tasks = plan["arrays"][array]["tasks"];
  if (index < 0 || index >= static_cast<int>(tasks.size()))
    Fail("{}: array {} has tasks 0..{}, not {}", where, array, tasks.size() - 1, index);
  const nlohmann::json& t = tasks[index];
  const fs::path result = dir / "results" / (t["id"].get<std::string>() + ".json");
  if (fs::exists(result) && ReadJsonFile(result).value("status", "") == "ok") {
    fmt::print("bench task: {} is done already ({})\n", t["id"].get<std::string>(), result.string());
    return true;
  }
  SceneSpec scene;
  scene.name = t["scene"].get<std::string>();
  if (!t["region"].is_null()) scene.region = t["region"].get<std::array<double, 4>>();
  PreparedScene prepared{&scene, t["scene_dir"].get<std::string>(), t["data_checksum"].get<std::string>()};
  RunSpec spec;
  spec.id = t["id"];
  for (const nlohmann::json& l : t["labels"]) spec.labels.push_back(RunLabel::FromJson(l, where));
  spec.method = t["method"];
  spec.scene = scene.name;
  spec.prepared = &prepared;
  spec.budget = {t["budget"]["iterations"].get<std::int64_t>(), t["budget"]["seconds"].get<double>()};
  spec.train_args = t["train_args"].get<std::vector<std::string>>();
  spec.render_args = t["render_args"].get<std::vector<std::string>>();
  spec.identity = t["identity"];
  const nlohmann::json& res = t["resources"];
  spec.resources = {res["cpus"].get<int>(), res["memory_gb"].get<double>(), res["minutes"].get<double>()};
  int threads = spec.resources.cpus;
  if (const char* c = std::getenv("SLURM_CPUS_PER_TASK"); c && std::atoi(c) > 0) threads = std::atoi(c);
  const std::optional<RunRecord> record = ExecuteRun(
      spec, {.runs_dir = dir / "runs", .hdr4d = SelfExecutable(), .threads = threads, .source = "slurm"});
  if (!record) Fail("bench task: run {} was cancelled", spec.id);
  WriteJsonFile(result, record->ToJson());
  fmt::print("bench task: {} {} -> {}\n", spec.id, record->status, result.string());
  if (record->status != "ok") fmt::print(stderr, "hdr4d: error: run {} failed: {}\n", spec.id, record->error);
  return record->status == "ok";
}

namespace {

// plan.json's run ids with their labels; nullopt without a plan. A malformed plan is an error
// naming it and the key.
std::optional<std::map<std::string, std::vector<RunLabel>>> PlannedRuns(const fs::path& dir) {
  const fs::path file = dir / "plan.json";
  if (!fs::exists(file)) return std::nullopt;
  const nlohmann::json plan = ReadJsonFile(file);
  std::map<std::string, std::vector<RunLabel>> runs;
  try {
    for (const nlohmann::json& a : plan.at("arrays")) {
      for (const nlohmann::json& t : a.at("tasks")) {
        std::vector<RunLabel>& labels = runs[t.at("id").get<std::string>()];
        for (const nlohmann::json& l : t.at("labels"))
          labels.push_back(RunLabel::FromJson(l, file.string() + ": labels"));
      }
    }
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: not a bench slurm plan (arrays[].tasks[] with id and labels): {}", file.string(),
         e.what());
  }
  return runs;
}

// A result is merged only under the id its file is named after and, with a plan, only as the
// planned run with the plan's labels: a result whose id matched neither was merged (issue 51,
// case 18).
void RequirePlanned(const RunRecord& r, const fs::path& file, const std::string& id,
                    const std::optional<std::map<std::string, std::vector<RunLabel>>>& plan) {
  if (r.id != id) {
    Fail("{}: key 'id' is '{}', but this file holds the result of run {} only; not merged",
         file.string(), r.id, id);
  }
  if (!plan) return;
  const auto it = plan->find(r.id);
  if (it == plan->end()) Fail("{}: run {} is not in {}; not merged", file.string(), r.id, "plan.json");
  for (const RunLabel& l : r.labels) {
    if (std::find(it->second.begin(), it->second.end(), l) == it->second.end()) {
      Fail("{}: key 'labels': {}/{}/{}/{}/seed {} is not a label plan.json gives run {}; not merged",
           file.string(), l.suite, l.method, l.scene, l.supervision, l.seed, r.id);
    }
  }
}

// The result files to merge, each with the run id it must hold: a bench slurm folder's
// results/<id>.json, or the records a `bench run` kept in its runs folder, <id>/record.json, while
// its store was locked (benchmark/kept_records.h).
std::vector<std::pair<fs::path, std::string>> ResultFiles(const fs::path& dir) {
  std::vector<std::pair<fs::path, std::string>> files;
  if (fs::is_directory(dir / "results")) {
    for (const auto& e : fs::directory_iterator(dir / "results"))
      if (e.path().extension() == ".json") files.emplace_back(e.path(), e.path().stem().string());
  } else if (fs::is_directory(dir)) {
    for (const auto& e : fs::directory_iterator(dir))
      if (fs::exists(e.path() / kKeptRecordName))
        files.emplace_back(e.path() / kKeptRecordName, e.path().filename().string());
  }
  if (files.empty() && !fs::is_directory(dir / "results")) {
    Fail("{}: no results folder (not a bench slurm folder) and no <run id>/{} (not the runs "
         "folder of a bench run that kept results)", dir.string(), kKeptRecordName);
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

CollectSummary Collect(const fs::path& dir, const fs::path& store_path) {
  const std::vector<std::pair<fs::path, std::string>> files = ResultFiles(dir);
  const auto plan = PlannedRuns(dir);
  ResultsStore store(store_path);
  const std::set<std::string> ok = store.RunIds("ok");
  CollectSummary s;
  std::vector<std::string> bad;
  std::set<std::string> seen;
  // One bad file is reported and the others are merged all the same (issue 51, case 24).
  for (const auto& [f, id] : files) {
    try {
      const RunRecord r = RunRecord::FromJson(ReadJsonFile(f), f.string());
      RequirePlanned(r, f, id, plan);
      seen.insert(r.id);
      if (ok.count(r.id)) {
        store.AddLabels(r.id, r.labels);
        ++s.already;
        continue;
      }
      store.InsertRun(r);
      ++(r.status == "ok" ? s.merged : s.failed_runs);
    } catch (const Error& e) {
      bad.push_back(e.what());
      continue;
    } catch (const std::exception& e) {  // never expected; named all the same
      bad.push_back(f.string() + ": " + e.what());
      continue;
    }
    // Merged from a bench run's folder: the kept copy has served.
    std::error_code ec;
    if (f.filename() == kKeptRecordName) fs::remove(f, ec);
  }
  if (plan) {
    for (const auto& [id, labels] : *plan)
      if (!seen.count(id) && !ok.count(id)) ++s.missing;
  }
  s.bad_files = static_cast<int>(bad.size());
  if (!bad.empty()) {
    for (const std::string& b : bad) fmt::print(stderr, "bench collect: not merged: {}\n", b);
    Fail("bench collect: {} result file(s) could not be merged (listed above; the other {} were)",
         bad.size(), s.merged + s.failed_runs + s.already);
  }
  return s;
}

}  // namespace hdr4d::bench
