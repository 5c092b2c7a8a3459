#include "benchmark/stress.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>

#include "benchmark/machine.h"
#include "benchmark/stress_kit.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
using stress::Case;
using stress::Cases;
using stress::Ctx;
using stress::kNoCrash;

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
