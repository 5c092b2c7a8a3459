#include "benchmark/run_plan.h"

#include <fmt/format.h>

#include <map>

#include "benchmark/settings_flags.h"
#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/files/sha256.h"

namespace hdr4d::bench {

namespace {

// The contents of the files that train or render arguments name (a suite's `"config":
// "lego.json"`): the run identity held only the name, so an edited file was reported as
// stored (issue 51, case 16). Empty when no argument names a file, so the ids of runs without
// one stay as they were.
nlohmann::json ArgumentFileHashes(const std::vector<std::string>& train,
                                  const std::vector<std::string>& render) {
  nlohmann::json hashes = nlohmann::json::object();
  for (const std::vector<std::string>* args : {&train, &render}) {
    for (const std::string& a : *args) {
      if (a.empty() || a[0] == '-' || hashes.contains(a)) continue;
      if (InputFileProblem(a).empty()) hashes[a] = Sha256File(a);
    }
  }
  return hashes;
}

}  // namespace

std::string IdentityKeyWithoutVersion(const nlohmann::json& identity) {
  nlohmann::json rest = identity;
  if (rest.is_object()) rest.erase("code_version");
  return Sha256Hex(rest.dump());
}

std::vector<RunSpec> PlanRuns(const Suite& suite, const std::vector<PreparedScene>& scenes,
                              const std::string& code_version) {
  std::vector<RunSpec> runs;
  std::map<std::string, std::size_t> by_id;
  // Seeds outermost: an interrupted suite has whole tables for its first seeds.
  for (const std::int64_t seed : suite.seeds) {
    for (const PreparedScene& scene : scenes) {
      for (const MethodSpec& method : suite.methods) {
        const std::vector<std::string>& supervisions =
            method.supervision.empty() ? suite.supervision : method.supervision;
        for (const std::string& supervision : supervisions) {
          for (const Budget& budget : suite.budgets) {
            for (const Variant& variant : suite.variants) {
              const std::string where =
                  fmt::format("{}: method '{}'{}", suite.file.string(), method.name,
                              variant.name.empty() ? "" : ", variant '" + variant.name + "'");
              RunSpec r;
              r.method = method.name;
              r.scene = scene.spec->name;
              r.prepared = &scene;
              r.budget = budget;
              r.resources = method.resources.value_or(suite.resources);
              const nlohmann::json train =
                  MergeSettings(MergeSettings(suite.train, method.train), variant.train);
              const nlohmann::json render =
                  MergeSettings(MergeSettings(suite.render, method.render), variant.render);
              r.train_args = SettingsToArgs(train, budget.iterations, where);
              r.train_args.insert(r.train_args.end(),
                                  {"--seed", std::to_string(seed), "--supervision", supervision});
              if (budget.iterations > 0) {
                r.train_args.insert(r.train_args.end(),
                                    {"--iterations", std::to_string(budget.iterations)});
              }
              if (budget.seconds > 0) {
                r.train_args.insert(r.train_args.end(),
                                    {"--max-seconds", FormatNumber(budget.seconds)});
              }
              r.render_args = SettingsToArgs(render, budget.iterations, where);
              if (scene.spec->region) {
                const auto& g = *scene.spec->region;
                r.region = fmt::format("{},{},{},{}", g[0], g[1], g[2], g[3]);
              }
              r.identity = {{"train", r.train_args},
                            {"render", r.render_args},
                            {"data_checksum", scene.checksum},
                            {"code_version", code_version},
                            {"scoring_version", kScoringVersion},
                            {"region", r.region}};
              if (nlohmann::json files = ArgumentFileHashes(r.train_args, r.render_args);
                  !files.empty()) {
                r.identity["argument_files"] = std::move(files);
              }
              r.id = Sha256Hex(r.identity.dump()).substr(0, 20);
              if (suite.curve_points > 0 && budget.iterations > 0) {
                const std::int64_t every =
                    std::max<std::int64_t>(1, budget.iterations / suite.curve_points);
                r.train_args.insert(r.train_args.end(), {"--test-every", std::to_string(every)});
              }
              const RunLabel label{suite.name,     method.name,  scene.spec->name, supervision,
                                   seed,           budget.Label(), variant.name};
              if (auto it = by_id.find(r.id); it != by_id.end()) {
                runs[it->second].labels.push_back(label);
                continue;
              }
              r.labels.push_back(label);
              by_id[r.id] = runs.size();
              runs.push_back(std::move(r));
            }
          }
        }
      }
    }
  }
  return runs;
}

double WorkUnits(const RunSpec& run) {
  return run.budget.iterations > 0 ? static_cast<double>(run.budget.iterations)
                                   : run.budget.seconds;
}

}  // namespace hdr4d::bench
