// `hdr4d bench submit` as a user runs it: good renders are scored into the store; missing and
// extra frames, wrong sizes, NaN pixels, a bad meta file and a taken name are one-line errors
// that leave every stored row as it was.
#include <gtest/gtest.h>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

TEST(SubmitCli, ScoresExternalRendersAndRefusesBadOnes) {
  testing::TempDir dir;
  const fs::path scene = dir / "scene", renders = dir / "renders", store = dir / "store.db";
  const fs::path log = dir / "log.txt";
  ASSERT_TRUE(RunHdr4dArgs({"make-demo-scene", "--out", scene.string(), "--size", "24",
                            "--timestamps", "3", "--cameras", "3", "--spp", "1"}, log).result.ok());
  ASSERT_TRUE(RunHdr4dArgs({"synth-ldr", "--data", scene.string(), "--seed", "1"}, log).result.ok());
  ASSERT_TRUE(RunHdr4dArgs({"train", "--data", scene.string(), "--out", (dir / "run").string(),
                            "--iterations", "60", "--supervision", "ldr+hdr"}, log).result.ok());
  ASSERT_TRUE(RunHdr4dArgs({"render", "--run", (dir / "run").string(), "--out", renders.string()}, log)
                  .result.ok());
  WriteJsonFile(dir / "meta.json", {{"train_seconds", 120}, {"render_fps", 2.5}, {"notes", "CUDA code"}});
  auto submit = [&](const std::string& method, std::vector<std::string> extra = {}) {
    std::vector<std::string> a = {"bench", "submit", "--store", store.string(), "--method", method,
                                  "--scene", scene.string(), "--renders", renders.string(),
                                  "--supervision", "ldr+hdr"};
    a.insert(a.end(), extra.begin(), extra.end());
    return RunHdr4dArgs(a, log);
  };
  const Command good = submit("ExternalNet", {"--meta", (dir / "meta.json").string()});
  ASSERT_TRUE(good.result.ok()) << good.text;
  std::string before;
  {
    ResultsStore s(store, false);
    const auto runs = s.Summaries();
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(runs[0].source, "submit");
    EXPECT_EQ(runs[0].label.suite, "external");
    EXPECT_DOUBLE_EQ(runs[0].train_seconds, 120);
    EXPECT_TRUE(runs[0].metrics.count("psnr") && runs[0].metrics.count("mu_psnr"));
    before = s.Record(runs[0].run_id).ToJson().dump();
  }
  auto expect_refused = [&](const Command& c, const std::string& names) {
    EXPECT_EQ(c.result.exit_code, 1) << c.text;
    EXPECT_EQ(CountLines(c.text, "hdr4d: error:"), 1) << c.text;
    EXPECT_NE(c.result.error_line.find(names), std::string::npos) << c.result.error_line;
    ResultsStore s(store, false);
    ASSERT_EQ(s.Summaries().size(), 1u);
    EXPECT_EQ(s.Record(s.Summaries()[0].run_id).ToJson().dump(), before);
  };
  // The same name again is refused without --replace.
  expect_refused(submit("ExternalNet"), "--replace");
  // A missing frame.
  fs::path png;
  for (const auto& e : fs::directory_iterator(renders))
    if (e.path().extension() == ".png") png = e.path();
  fs::rename(png, dir / "aside.png");
  expect_refused(submit("Other"), png.filename().string());
  fs::rename(dir / "aside.png", png);
  // An extra image.
  fs::copy_file(png, renders / "not_a_test_view.png");
  expect_refused(submit("Other"), "not_a_test_view.png");
  fs::remove(renders / "not_a_test_view.png");
  // A wrong size.
  const std::string saved = testing::ReadTextFile(png);
  WriteImage(png, Image(12, 12, 3, Encoding::kSrgb));
  expect_refused(submit("Other"), png.filename().string());
  testing::WriteTextFile(png, saved);
  // A NaN pixel.
  fs::path exr;
  for (const auto& e : fs::directory_iterator(renders))
    if (e.path().extension() == ".exr") exr = e.path();
  Image nan = ReadImage(exr);
  nan.at(1, 1, 0) = NAN;
  WriteImage(exr, nan, {.format = PixelFormat::kFloat});
  expect_refused(submit("Other"), exr.filename().string());
  // A meta file with an unknown key.
  WriteJsonFile(dir / "bad_meta.json", {{"train_minutes", 3}});
  expect_refused(submit("Other", {"--meta", (dir / "bad_meta.json").string()}), "train_minutes");
}

}  // namespace
}  // namespace hdr4d::bench
