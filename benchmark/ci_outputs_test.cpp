// What a user reads from the ci suite's store (CTest fixture ci_store): the tables' shape and
// sanity, the Pareto charts, and the HTML report opened in headless Chromium with no console
// errors, every table and image shown, and a screenshot kept in build/test_artifacts/ci.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "benchmark/bench_test_util.h"
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
      const bool ldr_only = method == "4dgs", hdr_only = method == "4dgs-hdr";
      const bool hdr_key = key.rfind("mu_", 0) == 0 || key == "hdr_flip";
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

}  // namespace
}  // namespace hdr4d::bench
