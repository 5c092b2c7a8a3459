#include "benchmark/suite.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <sstream>
#include <set>

#include "benchmark/names.h"
#include "benchmark/scene_cache.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
using testing::ErrorOf;

nlohmann::json Minimal() {
  return nlohmann::json::parse(R"({
    "name": "t",
    "scenes": [{"name": "s", "path": "scene"}],
    "methods": [{"name": "m", "train": {"method": "hdr4dgs"}}],
    "budgets": [{"iterations": 100}]})");
}

std::string ErrorFor(nlohmann::json j) {
  return ErrorOf([&] { ParseSuite(j, "/x/suite.json"); });
}

TEST(Suite, MinimalSuiteHasDefaults) {
  const Suite s = ParseSuite(Minimal(), "/x/suite.json");
  EXPECT_EQ(s.name, "t");
  EXPECT_EQ(s.supervision, std::vector<std::string>{"ldr"});
  EXPECT_EQ(s.seeds, std::vector<std::int64_t>{0});
  ASSERT_EQ(s.variants.size(), 1u);
  EXPECT_EQ(s.scenes[0].path, "/x/scene");  // relative to the suite file
  EXPECT_EQ(s.budgets[0].Label(), "100it");
  EXPECT_EQ((Budget{.iterations = 10, .seconds = 2.5}).Label(), "10it+2.5s");
}

TEST(Suite, EveryMistakeNamesTheFileAndTheKey) {
  auto with = [](const char* pointer, nlohmann::json v) {
    nlohmann::json j = Minimal();
    j[nlohmann::json::json_pointer(pointer)] = v;
    return j;
  };
  EXPECT_NE(ErrorFor(with("/colour", 1)).find("unknown key 'colour'"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/scenes/0/datagen", {{"scene", "lego"}})).find("exactly one of"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/methods/0/train/seed", 3)).find("set by the harness"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/methods/0/supervision", {"hdr+ldr"})).find("hdr+ldr"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/budgets/0", nlohmann::json::object())).find("needs 'iterations'"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/seeds", {1, 1})).find("twice"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/methods/1", {{"name", "m"}})).find("listed twice"), std::string::npos);
  EXPECT_NE(ErrorFor(with("/scenes/0/region", {0.9, 0.9, 0.2, 0.2})).find("inside the image"), std::string::npos);
  nlohmann::json t = Minimal();
  t["tables"] = {{{"id", "a"}, {"rows", {{{"method", "m"}, {"supervision", "ldr"}}}}, {"reference", "zz"}}};
  EXPECT_NE(ErrorFor(t).find("reference 'zz'"), std::string::npos);
  nlohmann::json n = Minimal();
  n.erase("name");
  const std::string e = ErrorFor(n);
  EXPECT_NE(e.find("/x/suite.json"), std::string::npos) << e;
  EXPECT_NE(e.find("'name' missing"), std::string::npos) << e;
}

// Names from a suite became paths: a table id "../../x" or an absolute path, a scene named
// "../../../x", a method or variant with a '/' wrote outside --out (issue 51, case 9). Every
// name is refused where the suite is read, naming the file and the key; spaces and dashes stay.
TEST(Suite, NamesThatArePathsAreRefusedNamingTheKey) {
  auto with = [](const char* pointer, nlohmann::json v) {
    nlohmann::json j = Minimal();
    j[nlohmann::json::json_pointer(pointer)] = v;
    return j;
  };
  nlohmann::json table = Minimal();
  table["tables"] = {{{"id", "ok"}, {"rows", {{{"method", "m"}, {"supervision", "ldr"}}}}}};
  auto table_with = [&](const char* pointer, nlohmann::json v) {
    nlohmann::json j = table;
    j[nlohmann::json::json_pointer(pointer)] = v;
    return j;
  };
  const std::vector<std::pair<nlohmann::json, std::string>> cases = {
      {table_with("/tables/0/id", "../../x"), "suite.json.tables[0].id"},
      {table_with("/tables/0/id", "/tmp/victim"), "suite.json.tables[0].id"},
      {table_with("/tables/0/scenes", "a/b"), "suite.json.tables[0].scenes"},
      {table_with("/tables/0/rows/0/method", "x/y"), "suite.json.tables[0].rows[0].method"},
      {with("/scenes/0/name", "../../../x"), "suite.json.scenes[0].name"},
      {with("/scenes/0/name", ".."), "suite.json.scenes[0].name"},
      {with("/scenes/0/group", "g\\h"), "suite.json.scenes[0].group"},
      {with("/methods/0/name", "hdr4dgs/ldr"), "suite.json.methods[0].name"},
      {with("/variants", {{{"name", "grad/1e-3"}}}), "suite.json.variants[0].name"},
      {with("/name", "suite\nrm -rf"), "suite.json.name"},
      {with("/name", std::string(kMaxNameBytes + 1, 'a')), "suite.json.name"},
  };
  for (const auto& [suite, key] : cases) {
    const std::string e = ErrorFor(suite);
    EXPECT_NE(e.find("/x/" + key + ":"), std::string::npos) << key << ": " << e;
  }
  // Names, however odd, are still names.
  const Suite s = ParseSuite(with("/methods/0/name", "HDR-4DGS (ours) 2"), "/x/suite.json");
  EXPECT_EQ(s.methods[0].name, "HDR-4DGS (ours) 2");
}

// A suite of 10^6 seeds took 2.6 GB for a dry run; one planning more than kMaxSuiteRuns runs
// (seeds alone or a product of axes) is refused up front, stating the limit (issue 51, case 24).
TEST(Suite, HugeSuitesAreRefusedUpFrontWithTheLimit) {
  nlohmann::json seeds = Minimal();
  seeds["seeds"] = nlohmann::json::array();
  for (int i = 0; i < 1000000; ++i) seeds["seeds"].push_back(i);
  const std::string e = ErrorFor(seeds);
  EXPECT_NE(e.find("/x/suite.json.seeds"), std::string::npos) << e;
  EXPECT_NE(e.find(std::to_string(kMaxSuiteRuns)), std::string::npos) << e;
  // 101 seeds x 100 methods x 1 scene x 1 budget: each axis is small, the product is not.
  nlohmann::json product = Minimal();
  product["seeds"] = nlohmann::json::array();
  for (int i = 0; i < 101; ++i) product["seeds"].push_back(i);
  product["methods"] = nlohmann::json::array();
  for (int i = 0; i < 100; ++i) product["methods"].push_back({{"name", "m" + std::to_string(i)}});
  const std::string p = ErrorFor(product);
  EXPECT_NE(p.find("plans 10100 runs"), std::string::npos) << p;
  EXPECT_NE(p.find("at most " + std::to_string(kMaxSuiteRuns)), std::string::npos) << p;
  product["seeds"].erase(100);  // exactly the limit
  EXPECT_EQ(ErrorFor(product), "");
}

TEST(Suite, UnknownSuiteNameListsTheShippedOnes) {
  const std::string e = ErrorOf([] { LoadSuite("no-such-suite"); });
  EXPECT_NE(e.find("ci"), std::string::npos) << e;
  EXPECT_NE(e.find("paper"), std::string::npos) << e;
  EXPECT_NE(ErrorOf([] { LoadSuite("/nowhere/x.json"); }).find("no such suite file"), std::string::npos);
}

// The paper suite holds every configuration of Tables 1 and 4-7; the ci suite the same ones.
TEST(Suite, ShippedSuitesCoverThePapersTables) {
  const std::set<std::string> external = {"HexPlane", "HDR-NeRF", "HDR-HexPlane"};
  for (const char* name : {"paper", "ci", "speed", "proof", "tone-mappers", "pipelines"}) {
    const Suite s = LoadSuite(name);
    EXPECT_EQ(s.name, name);
    for (const TableSpec& t : s.tables)
      for (const TableRow& r : t.rows)
        EXPECT_TRUE(s.FindMethod(r.method) || external.count(r.method)) << name << " " << r.method;
  }
  const Suite paper = LoadSuite("paper"), ci = LoadSuite("ci");
  EXPECT_EQ(paper.scenes.size(), 8u);
  EXPECT_EQ(paper.seeds.size(), 3u);
  std::set<std::string> ids;
  for (const TableSpec& t : paper.tables) ids.insert(t.id);
  EXPECT_EQ(ids, (std::set<std::string>{"table1", "table2", "table4", "table5", "table6", "table7"}));
  ASSERT_EQ(paper.methods.size(), ci.methods.size());
  // The same settings, but for the grid methods' budget (rays per batch, grid sizes), which ci
  // scales down with its images, and settings set to null (the grid methods switch off some).
  const auto settings = [](nlohmann::json train) {
    for (const char* budget : {"rays", "grid-voxels", "time-grid"}) train.erase(budget);
    for (auto it = train.begin(); it != train.end();) it = it->is_null() ? train.erase(it) : ++it;
    return train;
  };
  for (std::size_t i = 0; i < paper.methods.size(); ++i) {
    EXPECT_EQ(paper.methods[i].name, ci.methods[i].name);
    EXPECT_EQ(settings(paper.methods[i].train), settings(ci.methods[i].train));
  }
  // Table 4 compares every tone mapper; Tables 6-7 every k and context learner of the paper.
  std::set<std::string> mappers, learners;
  for (const MethodSpec& m : paper.methods) {
    mappers.insert(m.train.value("tone-mapper", "dtm"));
    learners.insert(m.train.value("context-learner", "gru"));
  }
  EXPECT_EQ(mappers, (std::set<std::string>{"dtm", "mlp", "sigmoid", "reinhard", "durand"}));
  EXPECT_EQ(learners, (std::set<std::string>{"gru", "rnn", "lstm", "transformer"}));
}

// A datagen scene may carry more datagen flags (a camera pipeline): they reach the source and
// give the scene its own cache folder; without them the source and folder are as before.
TEST(Suite, DatagenFlagsMakeTheirOwnScene) {
  nlohmann::json j = Minimal();
  j["scenes"] = nlohmann::json::parse(R"([
    {"name": "a", "datagen": {"scene": "lego"}},
    {"name": "b", "datagen": {"scene": "lego", "flags": {"pipeline": "phone"}}},
    {"name": "c", "datagen": {"scene": "lego", "flags": {"pipeline": "auto-exposure"}}}])");
  const Suite s = ParseSuite(j, "/x/suite.json");
  EXPECT_FALSE(s.scenes[0].source.contains("flags"));
  EXPECT_EQ(s.scenes[1].source["flags"]["pipeline"], "phone");
  const std::filesystem::path a = CachedSceneDir(s.scenes[0], "/c"),
                              b = CachedSceneDir(s.scenes[1], "/c"),
                              c = CachedSceneDir(s.scenes[2], "/c");
  EXPECT_EQ(a, "/c/datagen/mini-s0/lego");
  EXPECT_NE(b, a);
  EXPECT_NE(b, c);
  EXPECT_EQ(b.filename(), "lego");
  j["scenes"][1]["datagen"]["flags"] = {{"seed", 3}};  // the harness's own flag
  EXPECT_NE(ErrorFor(j).find("seed"), std::string::npos);
}

// A datagen scene of another pipeline takes the renders of a cached one of the same scene,
// preset and seed (datagen --reuse-renders); the first one of a scene renders. A stand-in for
// hdr4d records its arguments and writes a dataset.
TEST(Suite, AnotherPipelineOfACachedSceneReusesItsRenders) {
  nlohmann::json j = Minimal();
  j["scenes"] = nlohmann::json::parse(R"([
    {"name": "fixed", "datagen": {"scene": "lego"}},
    {"name": "phone", "datagen": {"scene": "lego", "flags": {"pipeline": "phone"}}},
    {"name": "deer", "datagen": {"scene": "deer", "flags": {"pipeline": "phone"}}},
    {"name": "tank-val", "datagen": {"scene": "tank", "flags": {"val-every": 8}}}])");
  const Suite s = ParseSuite(j, "/x/suite.json");
  testing::TempDir dir;
  // What the stand-in writes as each scene: one frame (its image's bytes are all the checksum
  // reads) and a manifest.
  const std::filesystem::path tiny = dir / "tiny";
  WriteJsonFile(tiny / "transforms_train.json",
                nlohmann::json::parse(R"({"camera_angle_x": 0.7, "w": 4, "h": 4, "frames": [{"file_path": "a.png",
                  "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]], "time": 0,
                  "exposures": 1.0, "camera_id": 0}]})"));
  testing::WriteTextFile(tiny / "a.png", "x");
  testing::WriteTextFile(tiny / "manifest.json", "{}");
  const std::filesystem::path fake = dir / "hdr4d";
  testing::WriteTextFile(fake,
                         "#!/bin/sh\necho \"$@\" >> '" + (dir / "args.txt").string() + "'\n"
                         "while [ $# -gt 0 ]; do case $1 in --out) out=$2;; --scene) scene=$2;; "
                         "esac; shift; done\nmkdir -p \"$out/$scene\"\n"
                         "cp '" + tiny.string() + "'/* \"$out/$scene/\"\n");
  std::filesystem::permissions(fake, std::filesystem::perms::owner_all);
  const SceneCacheOptions o{.cache_dir = dir / "cache", .hdr4d = fake, .verbose = false};
  for (const SceneSpec& spec : s.scenes) PrepareScene(spec, o);
  const std::string args = testing::ReadTextFile(dir / "args.txt");
  const std::vector<std::string> lines = [&] {
    std::vector<std::string> out;
    std::stringstream in(args);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }();
  ASSERT_EQ(lines.size(), 4u) << args;
  EXPECT_EQ(lines[0].find("--reuse-renders"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("--reuse-renders " + (dir / "cache" / "datagen" / "mini-s0").string()),
            std::string::npos) << lines[1];
  EXPECT_EQ(lines[2].find("--reuse-renders"), std::string::npos) << lines[2];  // no deer yet
  // The suite's scenes keep the paper's splits: no val split unless its flags ask for one.
  for (int i = 0; i < 3; ++i) EXPECT_NE(lines[i].find("--val-every 0"), std::string::npos) << lines[i];
  EXPECT_EQ(lines[3].find("--val-every 0"), std::string::npos) << lines[3];
  EXPECT_NE(lines[3].find("--val-every 8"), std::string::npos) << lines[3];
}

// The pipelines suite: Tables 4, 6 and 7 per pipeline on the eight scenes.
TEST(Suite, PipelinesSuiteFilmsTheEightScenesThreeWays) {
  const Suite s = LoadSuite("pipelines");
  ASSERT_EQ(s.scenes.size(), 24u);
  std::map<std::string, std::set<std::string>> scenes_of;
  for (const SceneSpec& scene : s.scenes) {
    const std::string pipeline = scene.source.contains("flags")
                                     ? scene.source["flags"]["pipeline"].get<std::string>()
                                     : "fixed";
    EXPECT_EQ(pipeline, scene.group) << scene.name;
    scenes_of[scene.group].insert(scene.source["scene"].get<std::string>());
  }
  EXPECT_EQ(scenes_of.size(), 3u);
  for (const auto& [group, names] : scenes_of) EXPECT_EQ(names.size(), 8u) << group;
  EXPECT_EQ(s.seeds.size(), 3u);
  ASSERT_EQ(s.budgets.size(), 1u);
  EXPECT_EQ(s.budgets[0].iterations, 3000);
  EXPECT_EQ(s.tables.size(), 9u);
}

}  // namespace
}  // namespace hdr4d::bench
