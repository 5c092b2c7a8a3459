// `bench findings` on small in-memory run sets and one store written directly (no training):
// holds, does not hold and undecided from the paired tests, coverage, the chart's points, the
// errors for a bad table id.
#include "benchmark/findings.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "benchmark/report_findings.h"
#include "benchmark/tables.h"
#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {

Suite FindingSuite() {
  return ParseSuite(nlohmann::json::parse(R"({
    "name": "f",
    "scenes": [{"name": "s1", "group": "fixed", "path": "a"}, {"name": "s2", "group": "fixed", "path": "b"}],
    "methods": [{"name": "ref"}, {"name": "x"}, {"name": "y"}],
    "seeds": [0, 1, 2],
    "budgets": [{"iterations": 10}],
    "tables": [{"id": "main", "scenes": "fixed", "rows": [{"label": "R", "method": "ref", "supervision": "ldr"}]},
      {"id": "t4", "layout": "ablation", "scenes": "fixed", "reference": "R",
       "finding": "R is the best tone mapper", "rows": [
        {"label": "X", "method": "x", "supervision": "ldr"},
        {"label": "Y", "method": "y", "supervision": "ldr"},
        {"label": "R", "method": "ref", "supervision": "ldr"}]}]})"),
                    "/x/f.json");
}

RunSummary FindingRun(const std::string& method, const std::string& scene, int seed, double psnr) {
  RunSummary r;
  r.label = {"f", method, scene, "ldr", seed, "10it", ""};
  r.run_id = fmt::format("{}-{}-{}", method, scene, seed);
  r.status = "ok";
  r.source = "harness";
  r.metrics = {{"psnr", psnr}, {"mu_psnr", psnr - 3}};
  return r;
}

const double kSeedNoise[3] = {0.04, -0.03, -0.01};

// R at 20 / 24 dB (s1 / s2) plus seed noise; X and Y offset by dx, dy with noise of their own.
std::vector<RunSummary> Runs(double dx, double dy, int seeds = 3,
                             const std::vector<std::string>& scenes = {"s1", "s2"}) {
  std::vector<RunSummary> runs;
  for (const std::string& scene : scenes) {
    const double base = scene == "s1" ? 20 : 24;
    for (int s = 0; s < seeds; ++s) {
      runs.push_back(FindingRun("ref", scene, s, base + kSeedNoise[s]));
      runs.push_back(FindingRun("x", scene, s, base + dx + kSeedNoise[(s + 1) % 3]));
      runs.push_back(FindingRun("y", scene, s, base + dy + kSeedNoise[(s + 2) % 3]));
    }
  }
  return runs;
}

const Finding& Only(const std::vector<Finding>& f, const std::string& metric) {
  for (const Finding& x : f)
    if (x.metric == metric) return x;
  throw std::runtime_error("no finding for " + metric);
}

TEST(Findings, HoldsWhenTheReferenceBeatsEveryRowBeyondTheNoise) {
  const Suite s = FindingSuite();
  const std::vector<Finding> f = BuildFindings(s, Runs(-1.0, -2.0), {});
  ASSERT_EQ(f.size(), 2u);  // t4 x {psnr, mu_psnr}; the main table states no finding
  const Finding& psnr = Only(f, "psnr");
  EXPECT_EQ(psnr.claim, "R is the best tone mapper");
  EXPECT_EQ(psnr.pipeline, "fixed");
  EXPECT_EQ(psnr.verdict, "holds") << psnr.why;
  ASSERT_EQ(psnr.against.size(), 2u);
  EXPECT_EQ(psnr.against[0].label, "X");
  EXPECT_NEAR(psnr.against[0].test.mean_difference, -1.0, 1e-9);
  EXPECT_EQ(psnr.against[0].test.pairs, 6);
  EXPECT_EQ(psnr.against[0].outcome, "reference better");
  EXPECT_NEAR(psnr.reference_mean, 22.0, 1e-9);
  EXPECT_EQ(psnr.scenes_covered, (std::vector<std::string>{"s1", "s2"}));
  EXPECT_EQ(psnr.seeds, (std::vector<std::int64_t>{0, 1, 2}));
  const std::string md = FindingsMarkdown(f);
  EXPECT_NE(md.find("| R is the best tone mapper | fixed | psnr | **holds** |"), std::string::npos) << md;
  EXPECT_NE(md.find("X 21.000, -1.000, p = "), std::string::npos) << md;
  EXPECT_NE(md.find("2/2 scenes (s1, s2), seeds 0,1,2"), std::string::npos) << md;
  const std::string csv = FindingsCsv(f);
  EXPECT_NE(csv.find("t4,\"R is the best tone mapper\",fixed,psnr,\"holds\",\"R\",22.000000,\"X\",21.000000,-1.000000,"),
            std::string::npos) << csv;
}

TEST(Findings, DoesNotHoldWhenARowIsBetterAndUndecidedWithinTheNoise) {
  const Suite s = FindingSuite();
  const Finding worse = Only(BuildFindings(s, Runs(-1.0, 0.8), {}), "psnr");
  EXPECT_EQ(worse.verdict, "does not hold");
  EXPECT_EQ(worse.why, "Y beats R beyond the seed noise");
  EXPECT_EQ(worse.against[1].outcome, "row better");
  // Y's offset is below its noise: the reference is not shown better than Y.
  const Finding close = Only(BuildFindings(s, Runs(-1.0, 0.005), {}), "psnr");
  EXPECT_EQ(close.verdict, "undecided") << close.why;
  EXPECT_EQ(close.against[1].outcome, "within noise");
  EXPECT_NE(close.why.find("Y: within the seed noise"), std::string::npos) << close.why;
  // A row identical to the reference (k = 30 where a scene has fewer timestamps): undecided.
  std::vector<RunSummary> same = Runs(-1.0, -2.0);
  for (RunSummary& r : same)
    if (r.label.method == "y") r.metrics["psnr"] = (r.label.scene == "s1" ? 20 : 24) + kSeedNoise[r.label.seed];
  const Finding twin = Only(BuildFindings(s, same, {}), "psnr");
  EXPECT_EQ(twin.against[1].outcome, "identical");
  EXPECT_EQ(twin.verdict, "undecided");
  EXPECT_NE(twin.why.find("Y: identical results"), std::string::npos) << twin.why;
  // Lower is better: a FLIP-like metric flips the sides.
  std::vector<RunSummary> runs = Runs(-1.0, -2.0);
  for (RunSummary& r : runs) r.metrics["flip"] = 1.0 / r.metrics["psnr"];
  FindingsOptions o;
  o.metrics = {"flip"};
  const Finding flip = Only(BuildFindings(s, runs, o), "flip");
  EXPECT_EQ(flip.direction, -1);
  EXPECT_EQ(flip.verdict, "holds") << flip.why;
}

TEST(Findings, CoverageAndOneSeed) {
  const Suite s = FindingSuite();
  // One scene of two: the verdict covers it, and says so.
  const Finding part = Only(BuildFindings(s, Runs(-1.0, -2.0, 3, {"s2"}), {}), "psnr");
  EXPECT_EQ(part.verdict, "holds");
  EXPECT_EQ(part.scenes_covered, (std::vector<std::string>{"s2"}));
  EXPECT_NE(FindingsMarkdown({part}).find("1/2 scenes (s2), seeds 0,1,2"), std::string::npos);
  // The table cell has no seed spread (a scene has no runs): the finding's is over s2 alone.
  const double sd = SampleStdDev({24 + kSeedNoise[0], 24 + kSeedNoise[1], 24 + kSeedNoise[2]});
  EXPECT_EQ(part.reference_spread_scope, "covered");
  EXPECT_NEAR(part.reference_spread, sd, 1e-12);
  EXPECT_NE(FindingsMarkdown({part}).find(fmt::format("R 24.000 ± {:.3f} (mean and seed sd over the covered scenes)", sd)),
            std::string::npos) << FindingsMarkdown({part});
  const Finding full = Only(BuildFindings(s, Runs(-1.0, -2.0), {}), "psnr");
  EXPECT_EQ(full.reference_spread_scope, "all");
  // X has runs on s1 only (a table's rows filled one scene at a time): every mean shown is over
  // s1, where the pairs are, not R's over both scenes.
  std::vector<RunSummary> partial = Runs(-1.0, -2.0);
  std::erase_if(partial, [](const RunSummary& r) { return r.label.method == "x" && r.label.scene == "s2"; });
  const Finding s1 = Only(BuildFindings(s, partial, {}), "psnr");
  EXPECT_EQ(s1.scenes_covered, (std::vector<std::string>{"s1"}));
  EXPECT_NEAR(s1.reference_mean, 20.0, 1e-9);
  EXPECT_NEAR(s1.against[0].mean, 19.0, 1e-9);
  EXPECT_NEAR(s1.against[1].mean, 18.0, 1e-9);  // Y has both scenes; shown over s1 too
  // One seed on one scene: nothing to test against.
  const Finding one = Only(BuildFindings(s, Runs(-1.0, -2.0, 1, {"s1"}), {}), "psnr");
  EXPECT_EQ(one.verdict, "undecided");
  EXPECT_EQ(one.reference_spread_scope, "none");
  EXPECT_NE(FindingsMarkdown({one}).find("| R 20.040 |"), std::string::npos) << FindingsMarkdown({one});
  EXPECT_EQ(one.against[0].outcome, "not testable");
  EXPECT_NE(one.why.find("no pairs with two seeds"), std::string::npos) << one.why;
  // A metric no run has.
  FindingsOptions typo;
  typo.metrics = {"psnrr"};
  const Finding missing = BuildFindings(s, Runs(-1.0, -2.0), typo).at(0);
  EXPECT_EQ(missing.verdict, "undecided");
  EXPECT_EQ(missing.why, "no run of the table has the metric 'psnrr'");
  // No runs at all.
  const Finding none = Only(BuildFindings(s, {}, {}), "psnr");
  EXPECT_EQ(none.verdict, "undecided");
  EXPECT_TRUE(none.scenes_covered.empty());
  EXPECT_NE(FindingsMarkdown({none}).find("R (no runs)"), std::string::npos);
  EXPECT_NE(FindingsMarkdown({none}).find("X: no runs; Y: no runs"), std::string::npos);
  EXPECT_TRUE(FindingChart(s, {}, none, {}).first.empty());
}

TEST(Findings, ChartHasSeedDotsMeansAndSpreadBars) {
  const Suite s = FindingSuite();
  const std::vector<RunSummary> runs = Runs(-1.0, -2.0);
  FindingsOptions o;
  o.metrics = {"psnr"};
  const Finding f = BuildFindings(s, runs, o).at(0);
  const PlotPanel chart = FindingChart(s, runs, f, o);
  ASSERT_EQ(chart.first.size(), 4u);  // bars, seed dots, means, reference
  const PlotSeries &bars = chart.first[0], &dots = chart.first[1], &means = chart.first[2],
                   &ref = chart.first[3];
  EXPECT_EQ(dots.x.size(), 9u);  // 3 rows x 3 seeds
  EXPECT_EQ(means.point_labels, (std::vector<std::string>{"X", "Y"}));
  ASSERT_EQ(ref.y.size(), 1u);
  EXPECT_NEAR(ref.y[0], 22.0, 1e-9);
  EXPECT_EQ(ref.x[0], 3.0);
  ASSERT_EQ(bars.y.size(), 9u);  // (low, high, break) per row
  const double sd = SampleStdDev({22.04, 21.97, 21.99});
  EXPECT_NEAR(bars.y[7] - bars.y[6], 2 * sd, 1e-9);
  EXPECT_NO_THROW(RenderPlotSvg(chart.first, chart.second));

  // The paper's daggers in ASCII for the PNG's font.
  Suite daggers = s;
  daggers.tables[1].rows[0].label = "X\u2020";
  daggers.tables[1].rows[1].label = "Y\u2021 (\u00e9)";
  const PlotPanel ascii = FindingChart(daggers, runs, BuildFindings(daggers, runs, o).at(0), o);
  EXPECT_EQ(ascii.first[2].point_labels, (std::vector<std::string>{"X+", "Y++ (?)"}));
  EXPECT_NE(ascii.second.x_label.find("1 X+, 2 Y++ (?)"), std::string::npos) << ascii.second.x_label;
}

TEST(Findings, ThroughAStoreAndBadTables) {
  testing::TempDir dir;
  const Suite s = FindingSuite();
  {
    ResultsStore store(dir / "f.sqlite");
    for (const RunSummary& r : Runs(-1.0, 0.8)) {
      RunRecord rec;
      rec.id = r.run_id;
      rec.code_version = "v1";
      rec.config = {{"identity", {{"run", r.run_id}}}};
      rec.labels = {r.label};
      rec.frames.push_back({"f0", 0, 0, 0.1, {{"psnr", r.metrics.at("psnr")}}, {}});
      store.InsertRun(rec);
    }
  }
  const ResultsStore store(dir / "f.sqlite", /*create=*/false);
  FindingsOptions o;
  o.metrics = {"psnr"};
  const Finding f = BuildFindings(s, SuiteRuns(store, s), o).at(0);
  EXPECT_EQ(f.verdict, "does not hold");
  EXPECT_EQ(f.against.at(1).test.pairs, 6);
  o.table = "nope";
  EXPECT_THROW(BuildFindings(s, {}, o), Error);
  o.table = "main";
  try {
    BuildFindings(s, {}, o);
    ADD_FAILURE() << "a main table gave findings";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("words no finding"), std::string::npos) << e.what();
  }
  o.table = "";
  o.metrics = {};
  EXPECT_THROW(BuildFindings(s, {}, o), Error);
}

// Table 1's kind of finding: a main table that words one compares its reference with the rows it
// names (the paper's baselines, not its own variants) and leaves out, by name, the rows that have
// no run of the metric (GPU-only baselines no suite runs).
TEST(Findings, AMainTableWithAFindingComparesItsBaselinesAndLeavesOutRowsWithoutRuns) {
  const Suite s = ParseSuite(nlohmann::json::parse(R"({
    "name": "f",
    "scenes": [{"name": "s1", "group": "fixed", "path": "a"}, {"name": "s2", "group": "fixed", "path": "b"}],
    "methods": [{"name": "ref"}, {"name": "x"}, {"name": "y"}],
    "seeds": [0, 1, 2],
    "budgets": [{"iterations": 10}],
    "tables": [{"id": "table1", "scenes": "fixed", "reference": "Ours", "finding": "Ours beats every baseline",
       "finding_rows": ["X", "GPU-only"], "rows": [
        {"label": "X", "method": "x", "supervision": "ldr"},
        {"label": "GPU-only", "method": "HDR-NeRF", "supervision": "ldr"},
        {"label": "Ours", "method": "ref", "supervision": "ldr"},
        {"label": "Ours, variant", "method": "y", "supervision": "ldr"}]}]})"), "/x/f.json");
  FindingsOptions o;
  o.metrics = {"psnr"};
  // Y (our own variant) is better than the reference but not a baseline: not compared.
  const std::vector<Finding> f = BuildFindings(s, Runs(-1.0, +2.0), o);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].claim, "Ours beats every baseline");
  EXPECT_EQ(f[0].verdict, "holds") << f[0].why;
  ASSERT_EQ(f[0].against.size(), 1u);
  EXPECT_EQ(f[0].against[0].label, "X");
  EXPECT_EQ(f[0].left_out, (std::vector<std::string>{"GPU-only"}));
  EXPECT_NE(f[0].why.find("left out, no runs with this metric: GPU-only"), std::string::npos) << f[0].why;
  EXPECT_EQ(f[0].scenes_covered, (std::vector<std::string>{"s1", "s2"}));
  EXPECT_EQ(BuildFindings(s, Runs(+1.0, -2.0), o).at(0).verdict, "does not hold");

  nlohmann::json bad = nlohmann::json::parse(R"({"name": "f", "scenes": [{"name": "s1", "path": "a"}],
    "methods": [{"name": "ref"}], "budgets": [{"iterations": 10}], "tables": [{"id": "t", "finding_rows": ["R"],
    "rows": [{"label": "R", "method": "ref", "supervision": "ldr"}]}]})");
  try {
    ParseSuite(bad, "/x/bad.json");
    ADD_FAILURE() << "the reference accepted as a finding row";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("finding_rows"), std::string::npos) << e.what();
  }
}

TEST(Findings, DefaultClaimAndTheReportSection) {
  const Suite s = FindingSuite();
  TableSpec plain = s.tables[1];
  plain.finding.clear();
  EXPECT_EQ(FindingClaim(plain), "R beats each other row");
  int images = 0, tables = 0;
  const std::string html = FindingsHtml(s, Runs(-1.0, -2.0), {}, &images, &tables);
  EXPECT_NE(html.find("<td><b>holds</b></td>"), std::string::npos) << html.substr(0, 2000);
  EXPECT_EQ(images, 1);  // one chart per table: held-out LDR
  EXPECT_EQ(tables, 1);
  EXPECT_NE(html.find("data:image/svg+xml"), std::string::npos);
  Suite no_ablation = s;
  no_ablation.tables.resize(1);  // the main table only
  EXPECT_EQ(FindingsHtml(no_ablation, Runs(-1.0, -2.0), {}, &images, &tables), "");
}

}  // namespace
}  // namespace hdr4d::bench
