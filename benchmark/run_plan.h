// A suite expanded into runs: methods x scenes x supervision modes x seeds x budgets x variants,
// each with its `hdr4d train` / `hdr4d render` arguments and its identity. The identity is the
// SHA-256 (first 20 hex digits) of the resolved configuration (the train and render arguments
// the run is made with, thread count and curve sampling left out because they do not change
// what is learned), the code version and the data checksum; two labels that resolve to the same
// configuration are one run.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmark/run_record.h"
#include "benchmark/scene_cache.h"
#include "benchmark/suite.h"

namespace hdr4d::bench {

// Bumped whenever the harness's scoring changes what it stores (part of every identity).
inline constexpr int kScoringVersion = 1;

struct RunSpec {
  std::string id;
  std::vector<RunLabel> labels;  // first: the one shown in progress lines
  std::string method, scene;     // suite names (of the first label)
  const PreparedScene* prepared = nullptr;
  Budget budget;
  std::vector<std::string> train_args;   // after `hdr4d train --data D --out O --threads T`
  std::vector<std::string> render_args;  // after `hdr4d render --run R --out O --threads T`
  nlohmann::json identity;               // what the id hashes
  Resources resources;
  std::string region;  // "" or "x,y,w,h" fractions for the luminance region
};

// Throws hdr4d::Error when a method's settings cannot be resolved (e.g. a fraction of the
// iterations with a seconds-only budget). `scenes` must be in the suite's scene order.
std::vector<RunSpec> PlanRuns(const Suite& suite,
                              const std::vector<PreparedScene>& scenes,
                              const std::string& code_version);

// A run's identity without its code version, hashed: two runs with equal keys are the same
// configuration on the same data made by two code versions (`bench run --any-code-version`,
// for a suite run over several sessions whose code changes in between).
std::string IdentityKeyWithoutVersion(const nlohmann::json& identity);

// Budget iterations (or, with a seconds-only budget, the budget's seconds) still to do: the
// unit of the ETA.
double WorkUnits(const RunSpec& run);

}  // namespace hdr4d::bench
