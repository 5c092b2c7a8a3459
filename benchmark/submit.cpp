#include "benchmark/submit.h"

#include <set>

#include "benchmark/child_process.h"
#include "benchmark/machine.h"
#include "benchmark/names.h"
#include "benchmark/results_store.h"
#include "benchmark/run_plan.h"
#include "benchmark/scene_cache.h"
#include "benchmark/scoring.h"
#include "benchmark/suite.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/files/json_util.h"
#include "core/files/sha256.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;

nlohmann::json ReadSubmissionMeta(const fs::path& path) {
  if (path.empty()) return nlohmann::json::object();
  nlohmann::json meta = ReadJsonFile(path);
  if (!meta.is_object()) Fail("{}: the meta file must be a JSON object", path.string());
  static const std::set<std::string> kNumbers = {"train_seconds", "render_fps", "peak_rss_mb"};
  for (auto& [key, value] : meta.items()) {
    if (kNumbers.count(key)) {
      if (!value.is_number() || value.get<double>() < 0)
        Fail("{}: key '{}' must be a non-negative number, got {}", path.string(), key, value.dump());
    } else if (key == "gaussians" || key == "iterations") {
      value = JsonInteger(value, path.string(), key, 0);  // 1e3 is stored as 1000
    } else if (key == "code_version" || key == "notes") {
      if (!value.is_string()) Fail("{}: key '{}' must be a string", path.string(), key);
    } else if (key == "machine") {
      if (value.is_string()) value = {{"description", value}};  // text: kept as a description
      if (!value.is_object())  // what `bench collect` requires of an exported record
        Fail("{}: key 'machine' must be a JSON object or text, got {}", path.string(),
             value.dump());
    } else {
      Fail("{}: unknown key '{}' (known: train_seconds, render_fps, gaussians, peak_rss_mb, "
           "iterations, code_version, machine, notes)", path.string(), key);
    }
  }
  return meta;
}

namespace {

// The scene a submission is scored on: a scene of the suite (generated into the cache if needed)
// or a dataset folder, with the suite's name ("external" without one) and its region.
struct SubmittedScene {
  fs::path dir;
  std::string name, suite = "external";
  std::optional<std::array<double, 4>> region;
};

SubmittedScene ResolveScene(const SubmitOptions& o) {
  SubmittedScene scene;
  if (!o.suite.empty()) {
    const Suite suite = LoadSuite(o.suite);
    scene.suite = suite.name;
    if (suite.FindMethod(o.method))
      Fail("bench submit: --method {}: a method of suite '{}' (trained by `bench run`); a "
           "submission never replaces its runs: use another --method name", o.method, suite.name);
    if (const SceneSpec* s = suite.FindScene(o.scene)) {
      const PreparedScene p = PrepareScene(
          *s, {.cache_dir = o.cache_dir.empty() ? DefaultCacheDir() : o.cache_dir,
               .hdr4d = SelfExecutable()});
      scene.dir = p.dir;
      scene.name = s->name;
      scene.region = s->region;
    }
  }
  if (scene.dir.empty()) {
    if (!fs::exists(fs::path(o.scene) / "transforms_train.json"))
      Fail("bench submit: --scene {}: neither a dataset folder nor a scene of {}", o.scene,
           o.suite.empty() ? "a suite (give --suite)" : "suite '" + o.suite + "'");
    scene.dir = fs::absolute(o.scene).lexically_normal();
    if (!scene.dir.has_filename()) scene.dir = scene.dir.parent_path();  // "scene/": its name
    scene.name = scene.dir.filename().string();
  }
  return scene;
}

}  // namespace

RunRecord Submit(const SubmitOptions& o) {
  RequireName(o.method, "bench submit: --method");  // a name in tables and paths, never a path
  if (o.method.starts_with("-"))  // `--method=--help`: an option, not a name
    Fail("bench submit: --method {}: a method name may not start with '-'", o.method);
  const auto& modes = SupervisionModes();
  if (std::find(modes.begin(), modes.end(), o.supervision) == modes.end())
    Fail("bench submit: --supervision {} is not one of ldr, hdr, ldr+hdr", o.supervision);
  const nlohmann::json meta = ReadSubmissionMeta(o.meta);

  const SubmittedScene scene = ResolveScene(o);
  const fs::path& scene_dir = scene.dir;
  const Dataset dataset = LoadDataset(scene_dir, {.image_check = ImageCheck::kNone});
  const ScoredRenders scored =
      ScoreRenders(dataset, o.renders, {.strict = true, .region = scene.region});

  // Identity: what was submitted (the render bytes), on which data, under which label.
  std::string renders_listing;
  std::set<std::string> names;
  for (const Frame& f : dataset.test) {
    for (const std::string& n : {LdrRenderName(f), HdrRenderName(f)})
      if (fs::exists(o.renders / n) && names.insert(n).second)
        renders_listing += n + " " + Sha256File(o.renders / n) + "\n";
  }
  RunRecord r;
  r.source = "submit";
  r.data_checksum = DatasetChecksum(scene_dir);
  const nlohmann::json identity = {{"method", o.method},      {"supervision", o.supervision},
                                   {"seed", o.seed},          {"data_checksum", r.data_checksum},
                                   {"renders", Sha256Hex(renders_listing)},
                                   {"meta", meta},            {"scoring_version", kScoringVersion}};
  r.id = "sub-" + Sha256Hex(identity.dump()).substr(0, 16);
  r.labels = {{scene.suite, o.method, scene.name, o.supervision, o.seed, "external", ""}};
  r.frames = scored.frames;
  r.config = {{"identity", identity},
              {"submission", {{"renders", fs::absolute(o.renders).string()}, {"meta", meta}}},
              {"scoring",
               {{"region", scored.region},
                {"region_camera", scored.region_camera},
                {"scoring_version", kScoringVersion}}}};
  r.code_version = meta.value("code_version", "external");
  r.git_describe = "";
  r.machine = meta.contains("machine") ? meta["machine"] : nlohmann::json::object();
  r.scene_dir = scene_dir.string();
  r.run_dir = fs::absolute(o.renders).string();
  r.train_seconds = meta.value("train_seconds", std::nan(""));
  r.render_fps = meta.value("render_fps", std::nan(""));
  r.peak_rss_mb = meta.value("peak_rss_mb", std::nan(""));
  r.gaussians = meta.contains("gaussians") ? meta["gaussians"].get<std::int64_t>() : -1;
  r.iterations = meta.contains("iterations") ? meta["iterations"].get<std::int64_t>() : -1;
  r.started_at = r.finished_at = UtcNow();
  // `bench export` writes this record and `bench collect` reads it back: the same reader checks
  // it here, so a submission the store takes is one collect takes too.
  RunRecord::FromJson(r.ToJson(), o.meta.empty() ? "bench submit" : o.meta.string());

  ResultsStore store(o.store);
  store.InsertSubmission(r, o.replace);
  return r;
}

}  // namespace hdr4d::bench
