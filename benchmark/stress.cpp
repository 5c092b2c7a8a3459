#include "benchmark/stress.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>

#include "benchmark/machine.h"
#include "benchmark/stress_kit.h"
#include "core/files/atomic_file.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
using stress::Case;
using stress::Cases;
using stress::Ctx;
using stress::kNoCrash;

namespace {

// Marks a case folder as bench stress's own: only such a folder is emptied for a new run.
constexpr const char* kCaseMarker = ".hdr4d-stress-case";

// An empty case folder with its marker. An existing folder is emptied only when bench stress
// made it (its marker is there): `--out D` with the user's files in D/<case>/ emptied them
// (issue 51, case 5).
void PrepareCaseFolder(const fs::path& dir) {
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(dir, ec);
  if (fs::exists(link)) {
    if (!fs::is_directory(link)) {
      Fail("bench stress: {} exists and is not a folder bench stress made; refusing to replace it "
           "(choose another --out)", dir.string());
    }
    const bool empty = fs::is_empty(dir, ec);
    if (!empty && !fs::exists(dir / kCaseMarker, ec)) {
      Fail("bench stress: {} holds files bench stress did not make (no {} in it); refusing to "
           "empty it (choose another --out, or remove the folder yourself)", dir.string(),
           kCaseMarker);
    }
    fs::remove_all(dir, ec);
    if (ec) Fail("bench stress: cannot empty {}: {}", dir.string(), ec.message());
  }
  fs::create_directories(dir, ec);
  if (ec) Fail("bench stress: cannot create {}: {}", dir.string(), ec.message());
  WriteTextFileAtomic(dir / kCaseMarker, "made by hdr4d bench stress; emptied by its next run\n");
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
    PrepareCaseFolder(ctx.dir);
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
