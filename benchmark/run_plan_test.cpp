#include "benchmark/run_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <unistd.h>

namespace hdr4d::bench {
namespace {

Suite TwoBySuite(int curve_points = 0) {
  nlohmann::json j = nlohmann::json::parse(R"({
    "name": "t",
    "scenes": [{"name": "a", "path": "a"}, {"name": "b", "path": "b"}],
    "methods": [
      {"name": "dtm", "supervision": ["ldr", "ldr+hdr"], "train": {"method": "hdr4dgs"}},
      {"name": "same-as-dtm", "train": {"method": "hdr4dgs"}},
      {"name": "k5", "train": {"method": "hdr4dgs", "context-window": 5}}],
    "seeds": [0, 1],
    "budgets": [{"iterations": 100}, {"iterations": 200}],
    "train": {"densify-until": {"of_iterations": 0.5}}})");
  j["curve_points"] = curve_points;
  return ParseSuite(j, "/x/t.json");
}

std::vector<PreparedScene> Scenes(const Suite& s, const std::string& checksum_b = "bbb") {
  return {{&s.scenes[0], "/data/a", "aaa"}, {&s.scenes[1], "/data/b", checksum_b}};
}

TEST(RunPlan, ExpandsEveryAxisAndMergesIdenticalConfigurations) {
  const Suite s = TwoBySuite();
  const auto scenes = Scenes(s);
  const std::vector<RunSpec> runs = PlanRuns(s, scenes, "v1");
  // (2 + 1 + 1 supervisions x methods) x 2 scenes x 2 seeds x 2 budgets = 32 labels; "same-as-dtm"
  // (ldr) resolves to dtm's ldr runs: 24 runs.
  std::size_t labels = 0;
  for (const RunSpec& r : runs) labels += r.labels.size();
  EXPECT_EQ(labels, 32u);
  EXPECT_EQ(runs.size(), 24u);
  std::set<std::string> ids;
  for (const RunSpec& r : runs) ids.insert(r.id);
  EXPECT_EQ(ids.size(), runs.size());
  const auto shared = std::find_if(runs.begin(), runs.end(), [](const RunSpec& r) { return r.labels.size() == 2; });
  ASSERT_NE(shared, runs.end());
  EXPECT_EQ(shared->labels[0].method, "dtm");
  EXPECT_EQ(shared->labels[1].method, "same-as-dtm");
  // Seeds are the outer axis: the first half of the plan is seed 0.
  EXPECT_EQ(runs.front().labels[0].seed, 0);
  EXPECT_EQ(runs.back().labels[0].seed, 1);
}

TEST(RunPlan, ArgumentsCarryTheAxes) {
  const Suite s = TwoBySuite();
  const auto scenes = Scenes(s);
  const std::vector<RunSpec> runs = PlanRuns(s, scenes, "v1");
  const RunSpec& r = runs.front();
  const auto& a = r.train_args;
  auto value = [&](const std::string& flag) {
    const auto it = std::find(a.begin(), a.end(), flag);
    return it == a.end() || it + 1 == a.end() ? std::string("?") : *(it + 1);
  };
  EXPECT_EQ(value("--method"), "hdr4dgs");
  EXPECT_EQ(value("--seed"), "0");
  EXPECT_EQ(value("--supervision"), "ldr");
  EXPECT_EQ(value("--iterations"), "100");
  EXPECT_EQ(value("--densify-until"), "50");
}

TEST(RunPlan, IdentityFollowsConfigCodeAndDataOnly) {
  const Suite s = TwoBySuite();
  const auto scenes = Scenes(s);
  const auto a = PlanRuns(s, scenes, "v1");
  // Same inputs: same identities (resume finds them).
  const auto b = PlanRuns(s, scenes, "v1");
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].id, b[i].id);
  // Another code version changes every identity.
  const auto c = PlanRuns(s, scenes, "v2");
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NE(a[i].id, c[i].id);
  // Other data on scene b changes only scene b's runs.
  const auto other = Scenes(s, "changed");
  const auto d = PlanRuns(s, other, "v1");
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(a[i].id == d[i].id, a[i].labels[0].scene == "a") << a[i].labels[0].scene;
  // Sampling the PSNR curve does not change what is learned: same identities.
  const Suite curves = TwoBySuite(4);
  const auto scenes_c = Scenes(curves);
  const auto e = PlanRuns(curves, scenes_c, "v1");
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, e[i].id);
    EXPECT_NE(std::find(e[i].train_args.begin(), e[i].train_args.end(), "--test-every"), e[i].train_args.end());
  }
}

}  // namespace
}  // namespace hdr4d::bench

#include <filesystem>
#include <fstream>

namespace hdr4d::bench {
namespace {
// Issue 51, case 16: the identity held only the name of a `config` file the suite names, so an
// edited file was reported as stored. Its contents are part of the identity now.
TEST(RunPlan, IdentityFollowsTheContentsOfAConfigFile) {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("hdr4d_run_plan_config_" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << R"({"batch_size": 1})";
  nlohmann::json j = nlohmann::json::parse(R"({
    "name": "t", "scenes": [{"name": "a", "path": "a"}],
    "methods": [{"name": "m", "train": {"method": "hdr4dgs"}}],
    "seeds": [0], "budgets": [{"iterations": 100}]})");
  j["methods"][0]["train"]["config"] = file.string();
  const Suite s = ParseSuite(j, "/x/t.json");
  const std::vector<PreparedScene> scenes = {{&s.scenes[0], "/data/a", "aaa"}};
  const auto a = PlanRuns(s, scenes, "v1");
  EXPECT_EQ(PlanRuns(s, scenes, "v1")[0].id, a[0].id);
  std::ofstream(file) << R"({"batch_size": 2})";
  const auto b = PlanRuns(s, scenes, "v1");
  EXPECT_NE(a[0].id, b[0].id);
  std::filesystem::remove(file);
}
// --any-code-version's key: the same run made by two code versions has one key; another
// configuration or other data has another.
TEST(RunPlan, IdentityKeyLeavesOutOnlyTheCodeVersion) {
  const Suite s = TwoBySuite();
  const auto scenes = Scenes(s);
  const std::vector<RunSpec> v1 = PlanRuns(s, scenes, "v1");
  const std::vector<RunSpec> v2 = PlanRuns(s, scenes, "v2");
  const std::vector<RunSpec> other_data = PlanRuns(s, Scenes(s, "changed"), "v1");
  ASSERT_EQ(v1.size(), v2.size());
  std::set<std::string> keys;
  for (std::size_t i = 0; i < v1.size(); ++i) {
    EXPECT_NE(v1[i].id, v2[i].id);
    EXPECT_EQ(IdentityKeyWithoutVersion(v1[i].identity), IdentityKeyWithoutVersion(v2[i].identity));
    keys.insert(IdentityKeyWithoutVersion(v1[i].identity));
    const bool scene_b = v1[i].scene == "b";
    EXPECT_EQ(IdentityKeyWithoutVersion(other_data[i].identity) !=
                  IdentityKeyWithoutVersion(v1[i].identity),
              scene_b);
  }
  EXPECT_EQ(keys.size(), v1.size());  // every configuration its own key
}

}  // namespace
}  // namespace hdr4d::bench
