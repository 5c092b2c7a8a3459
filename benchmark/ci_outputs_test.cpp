// What a user reads from the ci suite's store (CTest fixture ci_store): the tables' shape and
// sanity, the Pareto charts, and the HTML report opened in headless Chromium with no console
// errors, every table and image shown, and a screenshot kept in build/test_artifacts/ci.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

fs::path Store() {
  const fs::path store = Artifacts("ci") / "store.db";
  if (!fs::exists(store)) ADD_FAILURE() << "no ci store: run the ci_store fixture (CiSuite.*) first";
  return store;
}

std::vector<std::vector<std::string>> ReadCsv(const fs::path& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        cells.push_back(cell);
        cell.clear();
      } else {
        cell.push_back(c);
      }
    }
    cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST(CiOutputs, TablesHaveThePapersShapeAndSaneValues) {
  const fs::path out = Artifacts("ci") / "tables";
  fs::remove_all(out);
  const Command c = RunHdr4dArgs({"bench", "table", "ci", "--store", Store().string(), "--out",
                                  out.string(), "--all-metrics", "--per-scene"},
                                 Artifacts("ci") / "outputs.log");
  ASSERT_TRUE(c.result.ok()) << c.text;
  const Suite suite = LoadSuite("ci");
  for (const TableSpec& spec : suite.tables) {
    for (const char* ext : {".md", ".tex", ".csv"})
      EXPECT_TRUE(fs::exists(out / (spec.id + ext))) << spec.id << ext;
    EXPECT_TRUE(fs::exists(out / (spec.id + "-all.csv")));
    const auto csv = ReadCsv(out / (spec.id + ".csv"));
    ASSERT_GT(csv.size(), 1u);
    const auto& h = csv[0];
    auto col = [&](const std::string& name) {
      return static_cast<std::size_t>(std::find(h.begin(), h.end(), name) - h.begin());
    };
    const std::size_t ncol = (spec.layout == "main") ? 10 : 4;  // with FLIP beside each SSIM
    EXPECT_EQ(csv.size() - 1, spec.rows.size() * ncol) << spec.id;
    std::map<std::string, int> best;  // column -> rows marked best
    for (std::size_t i = 1; i < csv.size(); ++i) {
      const auto& r = csv[i];
      const std::string key = r[col("key")], mean = r[col("mean")], method = r[col("method")];
      if (key.find("lpips") != std::string::npos) {
        EXPECT_EQ(mean, "not computable") << spec.id;
        continue;
      }
      if (!suite.FindMethod(method)) {
        EXPECT_EQ(mean, "") << spec.id << " external " << method;  // nothing invented
        continue;
      }
      // Plain 4DGS and HexPlane have no HDR output under LDR supervision, and no LDR output
      // under HDR supervision (4DGS*, HexPlane*).
      const bool grid = suite.FindMethod(method)->train.value("method", "") == "hexplane";
      const std::string supervision = r[col("supervision")];
      const bool ldr_only = method == "4dgs" || (grid && supervision == "ldr");
      const bool hdr_only = method == "4dgs-hdr" || (grid && supervision == "hdr");
      const bool hdr_key = key.rfind("mu_", 0) == 0 || key.rfind("hdr_flip", 0) == 0;
      const bool ldr_key = key == "psnr" || key == "ssim" || key == "flip";
      if ((ldr_only && hdr_key) || (hdr_only && ldr_key)) {
        EXPECT_EQ(mean, "") << spec.id << " " << method << " " << key;
        continue;
      }
      ASSERT_FALSE(mean.empty()) << spec.id << " " << method << " " << key;
      const double v = std::stod(mean);
      if (key.find("psnr") != std::string::npos) {
        EXPECT_GT(v, 3) << key;
        EXPECT_LT(v, 60) << key;
      } else if (key.find("ssim") != std::string::npos || key.find("flip") != std::string::npos) {
        EXPECT_GT(v, 0) << key;
        EXPECT_LE(v, 1) << key;
      } else {
        EXPECT_GT(v, 0) << key;  // minutes, fps
      }
      EXPECT_EQ(r[col("runs")], r[col("expected_runs")]) << spec.id << " " << method;
      EXPECT_FALSE(r[col("sd_over_seeds")].empty());  // two seeds: a spread
      if (r[col("best")] == "1") ++best[key];
      // Two seeds on two scenes: every quality column against the reference is testable.
      if (r[col("label")] != spec.reference && key != "train_minutes" && key != "fps") {
        EXPECT_FALSE(r[col("p_vs_reference")].empty()) << spec.id << " " << method << " " << key;
      }
    }
    for (const auto& [key, n] : best) EXPECT_GE(n, 1) << spec.id << " " << key;
    const std::string md = testing::ReadTextFile(out / (spec.id + ".md"));
    EXPECT_NE(md.find("Paired tests of " + spec.id), std::string::npos);
    EXPECT_NE(md.find("LPIPS: not computed"), std::string::npos);
    const std::string tex = testing::ReadTextFile(out / (spec.id + ".tex"));
    EXPECT_NE(tex.find("\\begin{tabular}"), std::string::npos);
    EXPECT_NE(tex.find("\\end{table}"), std::string::npos);
  }
  EXPECT_TRUE(fs::exists(out / "table4-mu_psnr-per-scene.md"));
}

TEST(CiOutputs, ParetoChartsPerSceneAndOverall) {
  const fs::path out = Artifacts("ci") / "pareto";
  fs::remove_all(out);
  const Command c = RunHdr4dArgs({"bench", "pareto", "ci", "--store", Store().string(), "--out", out.string()},
                                 Artifacts("ci") / "outputs.log");
  ASSERT_TRUE(c.result.ok()) << c.text;
  for (const char* scene : {"lego", "analytic", "overall"})
    for (const char* time : {"train", "render"})
      for (const char* ext : {".png", ".svg"})
        EXPECT_TRUE(fs::exists(out / (std::string("pareto_") + scene + "_" + time + ext))) << scene << time << ext;
  const auto csv = ReadCsv(out / "pareto.csv");
  int front = 0;
  for (std::size_t i = 1; i < csv.size(); ++i) front += csv[i].back() == "1";
  EXPECT_GT(csv.size(), 10u);
  EXPECT_GE(front, 6);  // at least one front point per scene and time
}

TEST(CiOutputs, ReportLoadsInHeadlessChromiumWithTablesAndImages) {
  const fs::path dir = Artifacts("ci");
  const fs::path html = dir / "report.html";
  const Command c = RunHdr4dArgs({"bench", "report", "ci", "--store", Store().string(), "--out", html.string()},
                                 dir / "outputs.log");
  ASSERT_TRUE(c.result.ok()) << c.text;
  if (std::system("command -v chromium >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "chromium is not installed (scripts/install-deps.sh installs it)";
  const fs::path profile = dir / "chromium-profile";
  fs::remove_all(profile);
  const std::vector<std::string> flags = {"--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                                          "--no-first-run", "--disable-background-networking",
                                          "--disable-component-update", "--disable-sync",
                                          "--user-data-dir=" + profile.string(),
                                          "--enable-logging=stderr", "--v=0", "--hide-scrollbars"};
  auto chromium = [&](std::vector<std::string> extra, const fs::path& log) {
    std::vector<std::string> argv = {"/usr/bin/chromium"};
    argv.insert(argv.end(), flags.begin(), flags.end());
    argv.insert(argv.end(), extra.begin(), extra.end());
    argv.push_back("file://" + fs::absolute(html).string());
    fs::remove(log);
    const ChildResult r = RunChild({.argv = argv, .log = log, .timeout_seconds = 120});
    return std::pair{r, testing::ReadTextFile(log)};
  };
  // The DOM after load: the page's own check counted tables and images and broken images.
  const auto [dom_run, dom] = chromium({"--virtual-time-budget=10000", "--dump-dom"}, dir / "chromium-dom.log");
  ASSERT_TRUE(dom_run.ok()) << dom;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom, m, std::regex("data-tables=\"(\\d+)\" data-images=\"(\\d+)\" data-broken-images=\"(\\d+)\"")))
      << dom.substr(0, 2000);
  const Suite suite = LoadSuite("ci");
  EXPECT_GE(std::stoi(m[1]), static_cast<int>(2 * suite.tables.size()));
  EXPECT_GE(std::stoi(m[2]), 20);  // renders, error maps, charts
  EXPECT_EQ(std::stoi(m[3]), 0);
  EXPECT_NE(dom.find("Page check:"), std::string::npos);
  // Nothing on the console: Chromium logs every console message (errors included) as CONSOLE.
  EXPECT_EQ(dom.find("CONSOLE"), std::string::npos) << dom.substr(dom.find("CONSOLE"), 500);
  fs::remove_all(profile);
  const fs::path shot = dir / "report_screenshot.png";
  fs::remove(shot);
  const auto [shot_run, shot_log] = chromium({"--screenshot=" + shot.string(), "--window-size=1400,4000"},
                                             dir / "chromium-screenshot.log");
  ASSERT_TRUE(shot_run.ok()) << shot_log;
  EXPECT_EQ(shot_log.find("CONSOLE"), std::string::npos);
  EXPECT_GT(fs::file_size(shot), 50000u);
  fs::remove_all(profile);
}

// Headless Chromium on a page: the DOM after load (--dump-dom) or a screenshot, with its log.
std::pair<ChildResult, std::string> Chromium(const fs::path& html, std::vector<std::string> extra,
                                             const fs::path& log) {
  const fs::path profile = log.parent_path() / "chromium-profile-submitted";
  fs::remove_all(profile);
  std::vector<std::string> argv = {"/usr/bin/chromium", "--headless", "--no-sandbox",
                                   "--disable-gpu", "--disable-quic", "--no-first-run",
                                   "--disable-background-networking", "--disable-component-update",
                                   "--disable-sync", "--user-data-dir=" + profile.string(),
                                   "--enable-logging=stderr", "--v=0", "--hide-scrollbars"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  argv.push_back("file://" + fs::absolute(html).string());
  fs::remove(log);
  const ChildResult r = RunChild({.argv = argv, .log = log, .timeout_seconds = 120});
  fs::remove_all(profile);
  return {r, testing::ReadTextFile(log)};
}

// Issue 52's proof: the ci suite's store plus a method submitted under a new name (the renders
// of HDR-4DGS's seed-0 runs, so its values are known) has its row in every table it fits, with
// "external" and its coverage, a paired test over the two scenes, its renders in the report,
// and `--methods` selects it (an unknown name is an error listing the known ones).
TEST(CiOutputs, ASubmittedMethodUnderANewNameHasItsRowsAndItsRenders) {
  const fs::path dir = Artifacts("ci"), store = dir / "submitted.db", log = dir / "submitted.log";
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(store.string() + suffix);
  {
    const ResultsStore source(Store(), false);  // copied run by run: the ci store stays as it is
    ResultsStore copy(store);
    for (const std::string& id : source.RunIds("ok")) copy.InsertRun(source.Record(id));
  }
  std::map<std::string, fs::path> renders;  // scene -> HDR-4DGS (LDR), seed 0
  for (const RunSummary& r : ResultsStore(store, false).Summaries("ci"))
    if (r.label.method == "hdr4dgs" && r.label.supervision == "ldr" && r.label.seed == 0)
      renders[r.label.scene] = fs::path(r.run_dir) / "renders";
  ASSERT_EQ(renders.size(), 2u);
  for (const auto& [scene, folder] : renders) {
    const Command c = RunHdr4dArgs({"bench", "submit", "--store", store.string(), "--suite", "ci",
                                    "--scene", scene, "--renders", folder.string(), "--method",
                                    "NewNet", "--cache", (dir / "cache").string()}, log);
    ASSERT_TRUE(c.result.ok()) << c.text;
  }
  const Command table = RunHdr4dArgs({"bench", "table", "ci", "--store", store.string()}, log);
  ASSERT_TRUE(table.result.ok()) << table.text;
  // Table 1 and the four ablation tables (LDR rows, HDR columns) each have the row.
  EXPECT_EQ(CountLines(table.text, "| 13 | NewNet (external; 2/2 scenes, 1 seed) | LDR |"), 1) << table.text;
  std::size_t rows = 0;
  for (std::size_t at = 0; (at = table.text.find("| NewNet (external; 2/2 scenes, 1 seed) | LDR |", at)) != std::string::npos; ++at)
    ++rows;
  EXPECT_EQ(rows, LoadSuite("ci").tables.size()) << table.text;
  EXPECT_NE(table.text.find("(over 2 scenes)"), std::string::npos) << table.text;
  // --methods: NewNet and the reference rows only; an unknown name lists the known ones.
  const Command only = RunHdr4dArgs({"bench", "table", "ci", "--store", store.string(), "--methods",
                                     "NewNet", "--table", "table4"}, log);
  ASSERT_TRUE(only.result.ok()) << only.text;
  EXPECT_NE(only.text.find("| 1 | DTM (ours) | LDR |"), std::string::npos) << only.text;
  EXPECT_NE(only.text.find("| 2 | NewNet (external; 2/2 scenes, 1 seed) | LDR |"), std::string::npos) << only.text;
  EXPECT_EQ(only.text.find("Reinhard"), std::string::npos) << only.text;
  const Command unknown = RunHdr4dArgs({"bench", "table", "ci", "--store", store.string(), "--methods", "NoSuchNet"}, log);
  EXPECT_EQ(unknown.result.exit_code, 1);
  EXPECT_NE(unknown.result.error_line.find("--methods NoSuchNet"), std::string::npos) << unknown.text;
  EXPECT_NE(unknown.result.error_line.find("NewNet"), std::string::npos) << unknown.text;
  // The report: its rows and its renders beside the others', every image loading.
  const fs::path html = dir / "submitted_report.html";
  const Command report = RunHdr4dArgs({"bench", "report", "ci", "--store", store.string(), "--out", html.string()}, log);
  ASSERT_TRUE(report.result.ok()) << report.text;
  const std::string page = testing::ReadTextFile(html);
  EXPECT_NE(page.find("NewNet (external; 2/2 scenes, 1 seed)"), std::string::npos);
  EXPECT_NE(page.find("alt=\"NewNet (ldr, external) LDR\""), std::string::npos);
  EXPECT_NE(page.find("alt=\"NewNet (ldr, external) HDR error\""), std::string::npos);
  if (std::system("command -v chromium >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "chromium is not installed (scripts/install-deps.sh installs it)";
  const auto [dom_run, dom] = Chromium(html, {"--virtual-time-budget=10000", "--dump-dom"}, dir / "chromium-submitted-dom.log");
  ASSERT_TRUE(dom_run.ok()) << dom;
  EXPECT_NE(dom.find("data-broken-images=\"0\""), std::string::npos) << dom.substr(0, 2000);
  EXPECT_EQ(dom.find("CONSOLE"), std::string::npos);
  // A screenshot of the page narrowed to NewNet and HDR-4DGS, kept for a person to look at.
  const fs::path narrow = dir / "submitted_report_newnet.html", shot = dir / "submitted_report_newnet.png";
  ASSERT_TRUE(RunHdr4dArgs({"bench", "report", "ci", "--store", store.string(), "--out", narrow.string(),
                            "--methods", "NewNet,hdr4dgs"}, log).result.ok());
  fs::remove(shot);
  const auto [shot_run, shot_log] = Chromium(narrow, {"--screenshot=" + shot.string(), "--window-size=1400,6000"},
                                             dir / "chromium-submitted-shot.log");
  ASSERT_TRUE(shot_run.ok()) << shot_log;
  EXPECT_GT(fs::file_size(shot), 50000u);
}

}  // namespace
}  // namespace hdr4d::bench
