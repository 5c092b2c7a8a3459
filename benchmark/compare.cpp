#include "benchmark/compare.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

// suite, method, scene, supervision, budget, variant
using CompareKey = std::tuple<std::string, std::string, std::string, std::string, std::string,
                             std::string>;
using SeedRuns = std::map<std::int64_t, const RunSummary*>;

// The columns of the paper's tables, in their order: what is compared unless asked otherwise.
const std::vector<std::string> kPaperMetrics = {"mu_psnr", "mu_ssim", "hdr_flip_aligned",
                                                "psnr",    "ssim",    "flip"};

int DirectionOf(const std::string& key) {
  for (const char* up : {"psnr", "ssim", "corr"})
    if (key.find(up) != std::string::npos) return 1;
  for (const char* down : {"lpips", "flip", "mse", "error", "rmse"})
    if (key.find(down) != std::string::npos) return -1;
  return 0;
}

// A run's configuration without its code version: the same for two versions of one run.
std::string IdentityWithoutVersion(const RunRecord& r) {
  nlohmann::json id = r.config.value("identity", nlohmann::json());
  if (!id.is_object()) return "";
  id.erase("code_version");
  return id.dump();
}

bool MatchesVersion(const RunRecord& r, const std::string& v) {
  return r.code_version.rfind(v, 0) == 0 ||
         (!r.git_describe.empty() && r.git_describe.find(v) != std::string::npos);
}

// A run's summary under one label: its metric means over the frames with a finite value of each
// key, as ResultsStore::Summaries.
RunSummary SummaryOf(const RunRecord& r, const RunLabel& label) {
  RunSummary s;
  s.label = label;
  s.run_id = r.id;
  s.status = r.status;
  s.source = r.source;
  s.code_version = r.code_version;
  s.data_checksum = r.data_checksum;
  std::map<std::string, std::pair<double, int>> sums;
  for (const FrameResult& f : r.frames) {
    for (const auto& [k, v] : f.metrics) {
      if (std::isinf(v)) ++s.identical_frames[k];
      if (!std::isfinite(v)) continue;
      sums[k].first += v;
      ++sums[k].second;
    }
  }
  for (const auto& [k, sum] : sums) s.metrics[k] = sum.first / sum.second;
  return s;
}

std::string VersionsListing(const std::vector<RunRecord>& records) {
  std::map<std::string, int> count;
  for (const RunRecord& r : records)
    ++count[r.code_version + (r.git_describe.empty() ? "" : " (" + r.git_describe + ")")];
  std::vector<std::string> out;
  for (const auto& [v, n] : count) out.push_back(fmt::format("{}: {} runs", v, n));
  return out.empty() ? "none" : fmt::format("{}", fmt::join(out, "; "));
}

}  // namespace

CompareSide StoreSide(const ResultsStore& store) {
  return {store.path().string(), store.Summaries()};
}

CompareSide VersionSide(const ResultsStore& store, const std::string& version) {
  std::vector<RunRecord> records;
  for (const std::string& id : store.RunIds("ok")) records.push_back(store.Record(id));
  // Labels by configuration: a run a later version replaced kept its identity, not its labels.
  std::map<std::string, std::vector<RunLabel>> labels_of;
  std::set<std::string> matched;
  for (const RunRecord& r : records) {
    if (const std::string key = IdentityWithoutVersion(r); !key.empty())
      labels_of[key].insert(labels_of[key].end(), r.labels.begin(), r.labels.end());
    if (MatchesVersion(r, version)) matched.insert(r.code_version);
  }
  if (matched.empty())
    Fail("{}: no finished run of code version '{}' (versions in the store: {})",
         store.path().string(), version, VersionsListing(records));
  if (matched.size() > 1)
    Fail("{}: '{}' matches {} code versions ({}); give more of it",
         store.path().string(), version, matched.size(), fmt::join(matched, ", "));
  CompareSide side{fmt::format("code version {}", *matched.begin()), {}};
  for (const RunRecord& r : records) {
    if (r.code_version != *matched.begin()) continue;
    std::set<RunLabel> labels(r.labels.begin(), r.labels.end());
    if (labels.empty()) {
      const auto it = labels_of.find(IdentityWithoutVersion(r));
      if (it != labels_of.end()) labels.insert(it->second.begin(), it->second.end());
    }
    for (const RunLabel& l : labels) side.runs.push_back(SummaryOf(r, l));
  }
  return side;
}

namespace {

std::map<CompareKey, SeedRuns> ByConfiguration(const CompareSide& side, const CompareOptions& o) {
  std::map<CompareKey, SeedRuns> out;
  for (const RunSummary& r : side.runs) {
    const RunLabel& l = r.label;
    if (r.status != "ok" || (!o.suite.empty() && l.suite != o.suite)) continue;
    out[{l.suite, l.method, l.scene, l.supervision, l.budget, l.variant}][l.seed] = &r;
  }
  return out;
}

// The metrics of a configuration both sides have (in the paper's order, or every shared key).
std::vector<std::string> SharedMetrics(const SeedRuns& a, const SeedRuns& b,
                                       const CompareOptions& o) {
  std::set<std::string> in_a, in_b;
  for (const auto& [seed, r] : a)
    for (const auto& [k, v] : r->metrics) in_a.insert(k);
  for (const auto& [seed, r] : b)
    for (const auto& [k, v] : r->metrics) in_b.insert(k);
  std::vector<std::string> wanted = o.metrics;
  if (wanted.empty()) wanted = kPaperMetrics;
  if (wanted == std::vector<std::string>{"all"}) wanted.assign(in_a.begin(), in_a.end());
  std::vector<std::string> out;
  for (const std::string& k : wanted)
    if (in_a.count(k) && in_b.count(k)) out.push_back(k);
  return out;
}

// A --metrics key neither side has was reported as no configuration in common.
void CheckMetricNames(const CompareSide& a, const CompareSide& b, const CompareOptions& o) {
  if (o.metrics == std::vector<std::string>{"all"}) return;
  std::vector<RunSummary> runs;
  for (const CompareSide* side : {&a, &b})
    for (const RunSummary& r : side->runs)
      if (o.suite.empty() || r.label.suite == o.suite) runs.push_back(r);
  const std::set<std::string> known = MetricKeys(runs);
  const std::string whose = fmt::format("runs of {} and {}{}", a.name, b.name,
                                        o.suite.empty() ? "" : " in suite '" + o.suite + "'");
  for (const std::string& m : o.metrics) RequireMetricKey("--metrics", m, known, whose);
}

// Pairs of one configuration and metric over the seeds both sides have: (scene, B, A).
void AddPairs(const std::string& scene, const SeedRuns& a, const SeedRuns& b,
              const std::string& metric, std::vector<PairedValue>* pairs) {
  for (const auto& [seed, ra] : a) {
    const auto it = b.find(seed);
    if (it == b.end()) continue;
    const auto va = ra->metrics.find(metric), vb = it->second->metrics.find(metric);
    if (va != ra->metrics.end() && vb != it->second->metrics.end())
      pairs->push_back({scene, vb->second, va->second});
  }
}

CompareLine LineOf(const CompareKey& k, const std::string& metric,
                   const std::vector<PairedValue>& pairs, double alpha) {
  CompareLine line{std::get<0>(k), std::get<1>(k), std::get<2>(k), std::get<3>(k),
                   std::get<4>(k), std::get<5>(k), metric, DirectionOf(metric)};
  std::vector<double> a, b;
  for (const PairedValue& p : pairs) b.push_back(p.a), a.push_back(p.b);
  line.a = Mean(a);
  line.b = Mean(b);
  line.test = PairedSeedTest(pairs, alpha);
  if (!line.test.testable) {  // one seed per scene: the scenes are the pairs
    std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> by_scene;
    for (const PairedValue& p : pairs) {
      by_scene[p.scene].first.push_back(p.a);
      by_scene[p.scene].second.push_back(p.b);
    }
    std::vector<PairedValue> scenes;
    for (const auto& [s, v] : by_scene) scenes.push_back({"", Mean(v.first), Mean(v.second)});
    if (PairedTest t = PairedSeedTest(scenes, alpha); t.testable) {
      line.test = t;
      line.test.over_scenes = true;
      line.test.scenes = static_cast<int>(scenes.size());
    }
  }
  return line;
}

std::string OnlyIn(const std::string& side, const std::vector<CompareKey>& keys) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < keys.size() && i < 5; ++i)
    names.push_back(fmt::format("{}/{}/{}/{}", std::get<0>(keys[i]), std::get<1>(keys[i]),
                                std::get<2>(keys[i]), std::get<3>(keys[i])));
  return fmt::format("{} configuration(s) only in {}, not compared: {}{}", keys.size(), side,
                     fmt::join(names, ", "), keys.size() > 5 ? ", ..." : "");
}

}  // namespace

std::string CompareLine::Verdict() const {
  if (!test.testable) return "undecided";
  if (test.mean_difference == 0 && test.seed_sd == 0) return "same";
  if (!test.significant) return "undecided";
  if (direction == 0) return "differs";
  return test.mean_difference * direction > 0 ? "B better" : "A better";
}

Comparison Compare(const CompareSide& a, const CompareSide& b, const CompareOptions& o) {
  Comparison c{a.name, b.name, {}, {}, {}};
  const std::map<CompareKey, SeedRuns> ia = ByConfiguration(a, o), ib = ByConfiguration(b, o);
  CheckMetricNames(a, b, o);
  std::vector<CompareKey> only_a, only_b;
  // Per method (scene left empty): the pairs of every scene.
  std::map<std::pair<CompareKey, std::string>, std::vector<PairedValue>> per_method;
  for (const auto& [key, runs_a] : ia) {
    const auto it = ib.find(key);
    if (it == ib.end()) {
      only_a.push_back(key);
      continue;
    }
    for (const std::string& metric : SharedMetrics(runs_a, it->second, o)) {
      std::vector<PairedValue> pairs;
      AddPairs(std::get<2>(key), runs_a, it->second, metric, &pairs);
      if (pairs.empty()) continue;
      c.per_configuration.push_back(LineOf(key, metric, pairs, o.alpha));
      CompareKey method_key = key;
      std::get<2>(method_key) = "";
      auto& all = per_method[{method_key, metric}];
      all.insert(all.end(), pairs.begin(), pairs.end());
    }
  }
  for (const auto& [key, runs_b] : ib)
    if (!ia.count(key)) only_b.push_back(key);
  for (const auto& [km, pairs] : per_method)
    c.per_method.push_back(LineOf(km.first, km.second, pairs, o.alpha));
  if (!only_a.empty()) c.notes.push_back(OnlyIn("A", only_a));
  if (!only_b.empty()) c.notes.push_back(OnlyIn("B", only_b));
  if (c.per_configuration.empty())
    Fail("bench compare: {} and {} have no configuration (suite, method, scene, supervision, "
         "budget, variant) with a metric in common{}", a.name, b.name,
         o.suite.empty() ? "" : " in suite '" + o.suite + "'");
  return c;
}

}  // namespace hdr4d::bench
