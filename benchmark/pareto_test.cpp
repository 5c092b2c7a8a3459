#include "benchmark/pareto.h"
#include "benchmark/report.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace hdr4d::bench {
namespace {

TEST(Pareto, FrontKeepsOnlyUndominatedPoints) {
  std::vector<ParetoPoint> p(5);
  const double data[5][2] = {{1, 20}, {2, 25}, {3, 24}, {4, 30}, {2, 25}};  // the last ties the 2nd
  for (int i = 0; i < 5; ++i) p[i].seconds = data[i][0], p[i].quality = data[i][1];
  MarkFront(&p);
  EXPECT_TRUE(p[0].front);
  EXPECT_TRUE(p[1].front);
  EXPECT_FALSE(p[2].front);  // (2, 25) is faster and better
  EXPECT_TRUE(p[3].front);
  EXPECT_TRUE(p[4].front);  // equal points do not dominate each other
}

TEST(Pareto, PointsAverageSeedsAndOverallNeedsEveryScene) {
  const Suite suite = ParseSuite(nlohmann::json::parse(R"({"name": "t",
      "scenes": [{"name": "s1", "path": "a"}, {"name": "s2", "path": "b"}],
      "methods": [{"name": "m"}, {"name": "n"}], "budgets": [{"iterations": 1}]})"),
                                 "/x/t.json");
  std::vector<RunSummary> runs;
  auto add = [&](const std::string& m, const std::string& scene, const std::string& budget,
                 int seed, double secs, double q) {
    RunSummary r;
    r.label = {"t", m, scene, "ldr", seed, budget, ""};
    r.status = "ok";
    r.source = "harness";
    r.train_seconds = secs;
    r.render_fps = 100;
    r.metrics = {{"mu_psnr", q}};
    runs.push_back(r);
  };
  add("m", "s1", "100it", 0, 10, 20);
  add("m", "s1", "100it", 1, 12, 22);
  add("m", "s2", "100it", 0, 20, 30);
  add("m", "s1", "200it", 0, 30, 25);
  add("m", "s2", "200it", 0, 40, 35);
  add("n", "s1", "100it", 0, 5, 10);  // n has no run on s2: left out of the overall points
  const auto s1 = ParetoPoints(runs, suite, "mu_psnr", ParetoTime::kTraining, "s1");
  ASSERT_EQ(s1.size(), 3u);
  for (const ParetoPoint& p : s1) {
    if (p.method == "m" && p.budget == "100it") {
      EXPECT_DOUBLE_EQ(p.seconds, 11);
      EXPECT_DOUBLE_EQ(p.quality, 21);
      EXPECT_EQ(p.seeds, 2);
    }
    EXPECT_TRUE(p.front);  // each is faster or better than the others
  }
  const auto overall = ParetoPoints(runs, suite, "mu_psnr", ParetoTime::kTraining, "");
  ASSERT_EQ(overall.size(), 2u);
  for (const ParetoPoint& p : overall) EXPECT_EQ(p.method, "m");
  const auto render = ParetoPoints(runs, suite, "mu_psnr", ParetoTime::kRender, "s1");
  EXPECT_DOUBLE_EQ(render.front().seconds, 10);  // ms per frame at 100 fps
}

// A store of submissions alone said no run had both the metric and a time; an unknown
// metric said the same. Each is named now.
TEST(Pareto, NothingToPlotSaysWhy) {
  const Suite suite = ParseSuite(nlohmann::json::parse(R"({"name": "t",
      "scenes": [{"name": "s1", "path": "a"}], "methods": [{"name": "m"}],
      "budgets": [{"iterations": 1}]})"), "/x/t.json");
  RunSummary r;
  r.label = {"t", "Ext", "s1", "ldr", 0, "", ""};
  r.status = "ok";
  r.source = "submit";
  r.metrics = {{"mu_psnr", 20}, {"psnr", 25}};
  testing::TempDir dir;
  ParetoOptions o;
  o.out = dir / "out";
  std::string e = testing::ErrorOf([&] { WritePareto({r}, suite, o); });
  EXPECT_NE(e.find("the only runs of suite 't' with 'mu_psnr' are submissions (bench submit), "
                   "which carry no training time: run time against error needs runs trained"),
            std::string::npos)
      << e;
  o.metric = "nosuch";
  e = testing::ErrorOf([&] { WritePareto({r}, suite, o); });
  EXPECT_NE(e.find("--metric nosuch: unknown metric key; the runs of suite 't' have: mu_psnr, "
                   "psnr"),
            std::string::npos)
      << e;
}

// `bench report --methods` selects the runs of its charts (and the scenes' renders) as the
// tables select rows: by method name, or by a table row's label (its method and supervision);
// the charts' points are then those runs' alone.
TEST(Pareto, ReportChartsShowTheSelectedMethodsOnly) {
  const Suite suite = ParseSuite(nlohmann::json::parse(R"({"name": "t",
      "scenes": [{"name": "s1", "path": "a"}],
      "methods": [{"name": "m"}, {"name": "n"}, {"name": "o"}], "budgets": [{"iterations": 1}],
      "tables": [{"id": "T", "title": "t", "rows": [{"label": "Row N", "method": "n",
                  "supervision": "hdr"}, {"label": "Row M", "method": "m", "supervision": "ldr"}]}]})"),
                                 "/x/t.json");
  std::vector<RunSummary> runs;
  for (const auto& [m, sup] : std::vector<std::pair<std::string, std::string>>{
           {"m", "ldr"}, {"n", "hdr"}, {"n", "ldr"}, {"o", "ldr"}}) {
    RunSummary r;
    r.label = {"t", m, "s1", sup, 0, "1it", ""};
    r.status = "ok";
    r.source = "harness";
    r.train_seconds = 10;
    r.render_fps = 100;
    r.metrics = {{"mu_psnr", 20.0}};
    runs.push_back(r);
  }
  EXPECT_EQ(ReportSelectedRuns(runs, suite, {}).size(), 4u);
  const auto labels = [&](const std::vector<std::string>& methods) {
    std::vector<std::string> out;
    for (const RunSummary& r : ReportSelectedRuns(runs, suite, methods))
      out.push_back(r.label.method + "/" + r.label.supervision);
    return out;
  };
  EXPECT_EQ(labels({"o"}), (std::vector<std::string>{"o/ldr"}));
  EXPECT_EQ(labels({"Row N", "o"}), (std::vector<std::string>{"n/hdr", "o/ldr"}));
  EXPECT_EQ(labels({"n"}), (std::vector<std::string>{"n/hdr", "n/ldr"}));
  const auto points = ParetoPoints(ReportSelectedRuns(runs, suite, {"Row N"}), suite, "mu_psnr",
                                   ParetoTime::kTraining, "s1");
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0].method, "n");
}

// A suite with a --reference variant: each family has its own front (issue 55), and the chart
// draws both; the overall front is still one.
TEST(Pareto, ReferenceVariantsHaveAFrontOfTheirOwn) {
  const Suite suite = ParseSuite(nlohmann::json::parse(R"({"name": "t",
      "scenes": [{"name": "s1", "path": "a"}], "methods": [{"name": "m"}],
      "budgets": [{"iterations": 1}],
      "variants": [{"name": "default"}, {"name": "reference", "train": {"reference": true}}]})"),
                                 "/x/t.json");
  EXPECT_TRUE(ReferenceVariant(suite, "reference"));
  EXPECT_FALSE(ReferenceVariant(suite, "default"));
  std::vector<RunSummary> runs;
  auto add = [&](const std::string& variant, const std::string& budget, double secs, double q) {
    RunSummary r;
    r.label = {"t", "m", "s1", "ldr", 0, budget, variant};
    r.status = "ok";
    r.source = "harness";
    r.train_seconds = secs;
    r.metrics = {{"psnr", q}};
    runs.push_back(r);
  };
  add("default", "1k", 10, 20);
  add("default", "2k", 20, 24);
  add("reference", "1k", 15, 20.5);  // slower, a little better: on both fronts
  add("reference", "2k", 30, 23.5);  // beaten by the default's 2k: on its own family's front only
  const auto points = ParetoPoints(runs, suite, "psnr", ParetoTime::kTraining, "s1");
  ASSERT_EQ(points.size(), 4u);
  for (const ParetoPoint& p : points) {
    EXPECT_EQ(p.reference, p.variant == "reference");
    EXPECT_TRUE(p.family_front) << p.variant << " " << p.budget;
    EXPECT_EQ(p.front, !(p.variant == "reference" && p.budget == "2k")) << p.budget;
  }
  std::vector<PlotSeries> series;
  PlotOptions o;
  ASSERT_TRUE(ParetoChart(runs, suite, "psnr", ParetoTime::kTraining, "s1", &series, &o));
  ASSERT_GE(series.size(), 2u);
  EXPECT_EQ(series[series.size() - 2].name, "front: default");
  EXPECT_EQ(series.back().name, "front: --reference");
  EXPECT_EQ(series.back().x.size(), 2u);
}

}  // namespace
}  // namespace hdr4d::bench
