#include "benchmark/tables.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
using testing::ErrorOf;

Suite TableSuite() {
  return ParseSuite(nlohmann::json::parse(R"({
    "name": "t",
    "scenes": [{"name": "s1", "path": "a"}, {"name": "s2", "path": "b"}, {"name": "r1", "group": "real", "path": "c"}],
    "methods": [{"name": "a"}, {"name": "b"}, {"name": "d"}],
    "seeds": [0, 1, 2],
    "budgets": [{"iterations": 10}],
    "tables": [{"id": "main", "rows": [
        {"label": "A", "method": "a", "supervision": "ldr"},
        {"label": "B", "method": "b", "supervision": "ldr"},
        {"label": "Ext", "method": "External", "supervision": "ldr"},
        {"label": "D", "method": "d", "supervision": "ldr"}], "reference": "B"},
      {"id": "abl", "layout": "ablation", "rows": [
        {"label": "A", "method": "a", "supervision": "ldr"},
        {"label": "B", "method": "b", "supervision": "ldr"}]}]})"),
                    "/x/t.json");
}

RunSummary Run(const std::string& method, const std::string& scene, int seed, double psnr,
               double mu_psnr, const std::string& status = "ok") {
  RunSummary r;
  r.label = {"t", method, scene, "ldr", seed, "10it", ""};
  r.run_id = method + scene + std::to_string(seed);
  r.status = status;
  r.source = "harness";
  r.train_seconds = 60 * (method == "a" ? 2 : 1);
  r.render_fps = 50;
  if (status == "ok") r.metrics = {{"psnr", psnr}, {"ssim", 0.8}, {"mu_psnr", mu_psnr}, {"mu_ssim", 0.7},
                                   {"aligned_mu_psnr", mu_psnr + 1}};
  return r;
}

std::vector<RunSummary> Runs() {
  std::vector<RunSummary> runs;
  const double noise[3] = {0.05, -0.03, -0.02};
  for (int seed = 0; seed < 3; ++seed) {
    for (const char* scene : {"s1", "s2"}) {
      const double base = std::string(scene) == "s1" ? 20 : 24;
      runs.push_back(Run("b", scene, seed, base + noise[seed], 15 + noise[seed]));
      // a: 1 dB better in PSNR on every pair; mu-PSNR the same up to noise of its own.
      runs.push_back(Run("a", scene, seed, base + 1 + noise[(seed + 1) % 3], 15 + noise[(seed + 2) % 3]));
    }
  }
  runs.push_back(Run("d", "s1", 0, 10, 10));  // d: only one of six runs, and a failure
  runs.push_back(Run("d", "s2", 0, 0, 0, "failed"));
  runs.push_back(Run("a", "r1", 0, 99, 99));  // another scene group: not in these tables
  return runs;
}

std::size_t Column(const Table& t, const std::string& key) {
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c].key == key) return c;
  ADD_FAILURE() << "no column " << key;
  return 0;
}

// A submission under a trained method's name took that method's cell (the index kept the last
// run of each method x supervision x scene x seed): two runs in one cell are an error now.
TEST(Tables, TwoRunsInOneCellAreAnErrorNotAPick) {
  const Suite s = TableSuite();
  std::vector<RunSummary> runs = Runs();
  RunSummary sub = bench::Run("b", "s1", 0, 40, 40);
  sub.run_id = "sub-1";
  sub.source = "submit";
  sub.label.budget = "external";
  runs.push_back(sub);
  const std::string e = ErrorOf([&] { BuildTable(s.tables[0], s, runs, {}); });
  EXPECT_NE(e.find("two runs of method 'b' (ldr) on scene 's1', seed 0: bs10 (harness) and "
                   "sub-1 (submit)"), std::string::npos) << e;
}

// Identical images (PSNR +inf) printed "inf" in the tables and were marked best.
TEST(Tables, InfinityIsNeverAValueOrTheBest) {
  const Suite s = TableSuite();
  std::vector<RunSummary> runs = Runs();
  for (RunSummary& r : runs) {
    if (r.label.method != "d") continue;
    r.metrics["psnr"] = INFINITY;  // a summary from before the means left +inf out
    r.identical_frames["psnr"] = 4;
  }
  const Table t = BuildTable(s.tables[0], s, runs, {});
  const std::size_t psnr = Column(t, "psnr");
  const RowResult& d = t.rows[3];
  ASSERT_EQ(d.label, "D");
  EXPECT_FALSE(d.cells[psnr].has_value);
  EXPECT_FALSE(d.cells[psnr].best);
  EXPECT_TRUE(t.rows[0].cells[psnr].best);
  EXPECT_EQ(d.identical_frames, 4);
  std::ostringstream all;
  for (const std::string& f : t.footnotes) all << f << "\n";
  EXPECT_NE(all.str().find("D: 4 frame value(s) of images identical"), std::string::npos)
      << all.str();
  EXPECT_EQ(FormatValue(INFINITY, 2), "n/a");
  EXPECT_EQ(FormatValue(-INFINITY, 2), "n/a");
}

// `bench table/findings/report --budget nosuch` printed empty tables instead of an error.
TEST(Tables, UnknownBudgetsAndVariantsAreListed) {
  const Suite s = TableSuite();
  TableOptions o;
  o.budget = "nosuch";
  std::string e = ErrorOf([&] { BuildTable(s.tables[0], s, Runs(), o); });
  EXPECT_NE(e.find("--budget nosuch: not a budget of suite 't' (known: 10it)"), std::string::npos)
      << e;
  o.budget = "10it";
  o.variant = "nosuch";
  e = ErrorOf([&] { BuildTable(s.tables[0], s, Runs(), o); });
  EXPECT_NE(e.find("--variant nosuch: not a variant of suite 't'"), std::string::npos) << e;
  EXPECT_EQ(TableBudget(s, ""), "10it");
}

// `bench table --hdr-keys foo bar` printed HDR columns of '-' without a word.
TEST(Tables, UnknownHdrKeysAreListed) {
  const Suite s = TableSuite();
  TableOptions o;
  o.hdr_psnr_key = "aligned_mu_psnr";
  o.hdr_ssim_key = "bar";
  const std::string e = ErrorOf([&] { BuildTable(s.tables[1], s, Runs(), o); });
  EXPECT_NE(e.find("--hdr-keys bar: unknown metric key; the runs of suite 't' have: "
                   "aligned_mu_psnr, mu_psnr, mu_ssim, psnr, ssim"),
            std::string::npos)
      << e;
  // No run, no key to check against: the table says it has no runs.
  EXPECT_NO_THROW(BuildTable(s.tables[1], s, {}, o));
}

TEST(Tables, MainLayoutMeansSpreadsBestAndTests) {
  const Suite s = TableSuite();
  const Table t = BuildTable(s.tables[0], s, Runs(), {});
  ASSERT_EQ(t.rows.size(), 4u);
  EXPECT_EQ(t.scenes, (std::vector<std::string>{"s1", "s2"}));
  std::vector<std::string> keys;
  for (const auto& c : t.columns) keys.push_back(c.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"mu_psnr", "mu_ssim", "hdr_flip_aligned", "lpips_hdr", "psnr",
                                            "ssim", "flip", "lpips", "train_minutes", "fps"}));
  EXPECT_EQ(t.columns[Column(t, "flip")].direction, -1);  // FLIP: lower is better
  const std::size_t psnr = Column(t, "psnr"), mu = Column(t, "mu_psnr"), time = Column(t, "train_minutes");
  const RowResult &a = t.rows[0], &b = t.rows[1], &ext = t.rows[2], &d = t.rows[3];
  // B: seed means over scenes are 22 + noise: mean 22, sd = sd of the noise.
  EXPECT_NEAR(b.cells[psnr].mean, 22.0, 1e-12);
  EXPECT_NEAR(b.cells[psnr].spread, SampleStdDev({0.05, -0.03, -0.02}), 1e-12);
  EXPECT_NEAR(a.cells[psnr].mean, 23.0, 1e-12);
  EXPECT_TRUE(a.cells[psnr].best);
  EXPECT_FALSE(b.cells[psnr].best);
  EXPECT_TRUE(b.cells[time].best);  // lower is better for time
  EXPECT_NEAR(a.cells[time].mean, 2.0, 1e-12);
  // Paired test against B: +1 dB exceeds seed noise; mu-PSNR differences are noise.
  EXPECT_TRUE(a.tests[psnr].significant) << a.tests[psnr].Verdict();
  EXPECT_NEAR(a.tests[psnr].mean_difference, 1.0, 1e-12);
  EXPECT_EQ(a.tests[psnr].pairs, 6);
  EXPECT_EQ(a.tests[psnr].dof, 4);
  EXPECT_FALSE(a.tests[mu].significant) << a.tests[mu].Verdict();
  EXPECT_FALSE(a.tests[time].testable);  // costs are not tested
  // External row without runs; D incomplete with a failure.
  EXPECT_EQ(ext.runs, 0);
  EXPECT_FALSE(ext.cells[psnr].has_value);
  EXPECT_EQ(d.runs, 1);
  EXPECT_EQ(d.failed, 1);
  EXPECT_FALSE(d.cells[psnr].complete());
  EXPECT_FALSE(d.cells[psnr].has_spread);
  // LPIPS says it cannot be computed.
  EXPECT_FALSE(t.columns[Column(t, "lpips")].computable);
}

TEST(Tables, FormatsHaveOneLinePerRowAndSayWhatIsMissing) {
  const Suite s = TableSuite();
  const Table t = BuildTable(s.tables[0], s, Runs(), {});
  const std::string md = ToMarkdown(t);
  EXPECT_NE(md.find("| 1 | A | LDR |"), std::string::npos) << md;
  EXPECT_NE(md.find("**23.00** ± 0.04"), std::string::npos) << md;
  EXPECT_NE(md.find("n/a"), std::string::npos);
  EXPECT_NE(md.find("LPIPS: not computed"), std::string::npos);
  EXPECT_NE(md.find("Ext: no runs in the store; not methods of this suite"), std::string::npos) << md;
  EXPECT_NE(md.find("bench submit --suite t --method NAME"), std::string::npos);
  EXPECT_NE(md.find("[1/6]"), std::string::npos) << md;  // D: 1 of 2 scenes x 3 seeds
  const std::string tests = PairedTestsMarkdown(t);
  EXPECT_NE(tests.find("+1.00, p = "), std::string::npos) << tests;
  EXPECT_NE(tests.find("**exceeds seed noise**"), std::string::npos);
  const std::string tex = ToLatex(t);
  EXPECT_NE(tex.find("\\toprule"), std::string::npos);
  EXPECT_NE(tex.find("\\textbf{23.00}"), std::string::npos) << tex;
  EXPECT_NE(tex.find("\\multicolumn{4}{c|}{HDR}"), std::string::npos) << tex;  // PSNR SSIM FLIP LPIPS
  const std::string csv = ToCsv(t);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 4 * 10);  // 4 rows x 10 columns
  EXPECT_NE(csv.find("not computable"), std::string::npos);
}

TEST(Tables, ProtocolsPickTheirKeysAndNewMetricsAppear) {
  const Suite s = TableSuite();
  TableOptions gt;
  gt.protocol = HdrProtocol::kGtMax;
  EXPECT_EQ(BuildTable(s.tables[1], s, Runs(), gt).columns[0].key, "mu_psnr_gt_max");
  gt.protocol = HdrProtocol::kPu21;
  EXPECT_EQ(BuildTable(s.tables[1], s, Runs(), gt).columns[1].key, "pu21_ssim");
  TableOptions aligned;
  aligned.hdr_psnr_key = "aligned_mu_psnr";
  aligned.hdr_ssim_key = "mu_ssim";
  const Table at = BuildTable(s.tables[1], s, Runs(), aligned);
  EXPECT_EQ(at.columns[0].key, "aligned_mu_psnr");
  EXPECT_NEAR(at.rows[1].cells[0].mean, 16.0, 1e-12);
  const Table all = BuildAllMetricsTable(s.tables[1], s, Runs(), {});
  std::vector<std::string> keys;
  for (const auto& c : all.columns) keys.push_back(c.key);
  // Known keys first in their order, then keys added later (here a scale-aligned metric).
  EXPECT_EQ(keys, (std::vector<std::string>{"psnr", "ssim", "mu_psnr", "mu_ssim", "aligned_mu_psnr",
                                            "gaussians", "peak_rss_mb"}));
  EXPECT_NEAR(all.rows[0].cells[4].mean, 16.0, 0.05);
}

TEST(Tables, PerSceneTableHasAMeanLine) {
  const Suite s = TableSuite();
  const Table t = BuildTable(s.tables[1], s, Runs(), {});
  const std::string md = PerSceneMarkdown(s.tables[1], s, Runs(), {}, t.columns[0]);
  EXPECT_NE(md.find("| s1 (3) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| mean over scenes |"), std::string::npos) << md;
}

// A submission under a name no table knows: one seed on both scenes, 0.5 dB above B on s1
// and 0.7 dB on s2, HDR metrics too.
RunSummary Submitted(const std::string& method, const std::string& scene, double psnr,
                     const std::string& supervision = "ldr") {
  RunSummary r = Run(method, scene, 0, psnr, 15);
  r.label.budget = "external";
  r.label.supervision = supervision;
  r.source = "submit";
  r.run_id = "sub-" + method + scene + supervision;
  return r;
}

TEST(Tables, EveryMethodGetsARowWhereItsLayoutFits) {
  const Suite s = TableSuite();
  std::vector<RunSummary> runs = Runs();
  runs.push_back(Submitted("MyNet", "s1", 20.5));
  runs.push_back(Submitted("MyNet", "s2", 24.7));
  runs.push_back(Submitted("HdrOnly", "s1", 30, "hdr"));  // not a supervision of the ablation
  const Table main = BuildTable(s.tables[0], s, runs, {});
  ASSERT_EQ(main.rows.size(), 6u);  // A, B, Ext, D, then HdrOnly and MyNet, by name
  const RowResult &hdr_only = main.rows[4], &mine = main.rows[5];
  EXPECT_EQ(mine.label, "MyNet");
  EXPECT_TRUE(mine.added && mine.external);
  EXPECT_EQ(CoverageText(mine, main.scenes.size()), "2/2 scenes, 1 seed");
  EXPECT_EQ(CoverageText(hdr_only, main.scenes.size()), "1/2 scenes, 1 seed");
  EXPECT_EQ(RowName(mine, 2), "MyNet (external; 2/2 scenes, 1 seed)");
  const std::size_t psnr = Column(main, "psnr");
  EXPECT_NEAR(mine.cells[psnr].mean, 22.6, 1e-12);
  EXPECT_EQ(mine.cells[psnr].expected, 2);  // its scenes x its one seed
  // One seed: the seed test cannot decide, the test over scenes can (+0.5 and +0.7 against
  // B's means over seeds, 20 and 24).
  const PairedTest& t = mine.tests[psnr];
  EXPECT_TRUE(t.testable && t.over_scenes) << t.Verdict();
  EXPECT_EQ(t.pairs, 2);
  EXPECT_NEAR(t.mean_difference, 0.6, 1e-12);
  EXPECT_EQ(t.dof, 1);
  EXPECT_NE(t.Verdict().find("scene-to-scene noise"), std::string::npos);
  const std::string md = ToMarkdown(main);
  EXPECT_NE(md.find("| 6 | MyNet (external; 2/2 scenes, 1 seed) | LDR |"), std::string::npos) << md;
  EXPECT_NE(md.find("HdrOnly, MyNet: not rows of this suite's tables"), std::string::npos) << md;
  EXPECT_NE(PairedTestsMarkdown(main).find("(over 2 scenes)"), std::string::npos);
  const std::string csv = ToCsv(main);
  EXPECT_NE(csv.find("external,added_row,coverage,test_over"), std::string::npos);
  EXPECT_NE(csv.find(",1,1,\"2/2 scenes, 1 seed\",scenes"), std::string::npos) << csv;
  // The ablation layout (HDR columns, LDR rows): MyNet fits, the HDR-supervised one does not.
  const Table abl = BuildTable(s.tables[1], s, runs, {});
  ASSERT_EQ(abl.rows.size(), 3u);
  EXPECT_EQ(abl.rows[2].label, "MyNet");
  // A suite method that no table names also gets its row; one with no runs on the table's
  // scenes does not.
  Suite with_c = s;
  with_c.methods.push_back({.name = "c", .label = "C method"});
  runs.push_back(bench::Run("c", "s1", 1, 21, 15));
  runs.push_back(bench::Run("c", "r1", 0, 21, 15));
  const Table m2 = BuildTable(with_c.tables[0], with_c, runs, {});
  ASSERT_EQ(m2.rows.size(), 7u);
  EXPECT_EQ(m2.rows[6].label, "C method");
  EXPECT_FALSE(m2.rows[6].external);
  EXPECT_EQ(RowName(m2.rows[6], 2), "C method (1/2 scenes, 1 seed)");
  EXPECT_EQ(m2.rows[6].expected, 6);  // a suite method: the suite's seeds
}

TEST(Tables, MethodsSelectRowsAndUnknownNamesAreListed) {
  const Suite s = TableSuite();
  std::vector<RunSummary> runs = Runs();
  runs.push_back(Submitted("MyNet", "s1", 20.5));
  TableOptions o;
  o.methods = {"MyNet", "A"};  // a method name and a row label
  const Table t = BuildTable(s.tables[0], s, runs, o);
  std::vector<std::string> labels;
  for (const RowResult& r : t.rows) labels.push_back(r.label);
  EXPECT_EQ(labels, (std::vector<std::string>{"A", "B", "MyNet"}));  // B: the reference stays
  EXPECT_TRUE(HasSelectedRows(t, o));
  EXPECT_NO_THROW(CheckRowNames(s, runs, o));
  o.methods = {"B"};
  EXPECT_FALSE(HasSelectedRows(BuildTable(s.tables[0], s, runs, o), o));
  o.methods = {"MyNet", "Nope"};
  try {
    CheckRowNames(s, runs, o);
    ADD_FAILURE() << "no error for an unknown name";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("--methods Nope"), std::string::npos) << m;
    EXPECT_NE(m.find("known: A, B, D, Ext, External, MyNet, a, b, d"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace hdr4d::bench
