// `hdr4d bench compare` on two small synthetic stores and on two code versions in one store:
// the differences per configuration, the paired verdicts (B better where it exceeds the seed
// noise, undecided where it does not or one seed cannot tell), Markdown and CSV.
#include "benchmark/compare.h"

#include <gtest/gtest.h>

#include "benchmark/bench_test_util.h"
#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

// One run with two frames whose metrics average to psnr and ssim.
RunRecord Record(const std::string& version, const std::string& scene, std::int64_t seed,
                 double psnr, double ssim, const std::string& method = "m") {
  RunRecord r;
  r.id = fmt::format("{}-{}-{}-{}", version, method, scene, seed);
  r.code_version = version;
  r.git_describe = "g" + version + "-dirty";
  r.config = {{"identity", {{"train", {method, scene, seed}}, {"code_version", version}}}};
  r.labels = {{"s", method, scene, "ldr", seed, "100it", ""}};
  for (int f = 0; f < 2; ++f)
    r.frames.push_back({fmt::format("f{}", f), 0.5 * f, 0, 0.1,
                        {{"psnr", psnr + (f ? 0.1 : -0.1)}, {"ssim", ssim}}, {}});
  return r;
}

const double kNoise[3] = {0.03, -0.05, 0.02};

// Side A at 20 dB (scene s1) and 24 dB (s2); side B +0.5 dB everywhere, SSIM moved by noise only.
void Fill(ResultsStore* store, const std::string& version, double gain, double ssim_shift,
          int seeds = 3) {
  for (const char* scene : {"s1", "s2"}) {
    const double base = std::string(scene) == "s1" ? 20 : 24;
    for (int seed = 0; seed < seeds; ++seed) {
      store->InsertRun(Record(version, scene, seed, base + gain + kNoise[seed],
                              0.8 + ssim_shift * kNoise[(seed + 1) % 3]));
    }
  }
}

const CompareLine& Line(const std::vector<CompareLine>& lines, const std::string& scene,
                        const std::string& metric) {
  for (const CompareLine& l : lines)
    if (l.scene == scene && l.metric == metric) return l;
  throw std::runtime_error("no line " + scene + " " + metric);
}

TEST(Compare, TwoStoresPerConfigurationWithPairedVerdicts) {
  testing::TempDir dir;
  ResultsStore a(dir / "a.db"), b(dir / "b.db");
  Fill(&a, "v1", 0, 0);
  Fill(&b, "v2", 0.5, 1);
  b.InsertRun(Record("v2", "s3", 0, 30, 0.9));  // only in B
  const Comparison c = Compare(StoreSide(a), StoreSide(b), {});
  ASSERT_EQ(c.per_configuration.size(), 4u);  // 2 scenes x (psnr, ssim)
  const CompareLine& psnr = Line(c.per_configuration, "s1", "psnr");
  EXPECT_NEAR(psnr.a, 20, 1e-9);
  EXPECT_NEAR(psnr.b, 20.5, 1e-9);
  EXPECT_NEAR(psnr.test.mean_difference, 0.5, 1e-9);
  EXPECT_EQ(psnr.test.pairs, 3);
  EXPECT_EQ(psnr.Verdict(), "B better");  // the same noise on both sides: exactly +0.5 each seed
  const CompareLine& ssim = Line(c.per_configuration, "s2", "ssim");
  EXPECT_EQ(ssim.Verdict(), "undecided") << ssim.test.Verdict();  // noise around zero
  const CompareLine& method = Line(c.per_method, "", "psnr");
  EXPECT_EQ(method.test.pairs, 6);
  EXPECT_EQ(method.Verdict(), "B better");
  ASSERT_EQ(c.notes.size(), 1u);
  EXPECT_NE(c.notes[0].find("1 configuration(s) only in B"), std::string::npos) << c.notes[0];
  const std::string md = CompareMarkdown(c);
  EXPECT_NE(md.find("| s | m | s1 | ldr | 100it | psnr | 20.000 | 20.500 | +0.500 | 3 |"),
            std::string::npos) << md;
  const std::string csv = CompareCsv(c);
  EXPECT_NE(csv.find("configuration,"), std::string::npos);
  EXPECT_NE(csv.find(",psnr,20.000000,20.500000,0.500000,3,seeds,"), std::string::npos) << csv;
  // A worse B: "A better".
  const Comparison reverse = Compare(StoreSide(b), StoreSide(a), {});
  EXPECT_EQ(Line(reverse.per_configuration, "s1", "psnr").Verdict(), "A better");
}

TEST(Compare, OneSeedIsUndecidedPerSceneAndTestedOverScenes) {
  testing::TempDir dir;
  ResultsStore a(dir / "a.db"), b(dir / "b.db");
  Fill(&a, "v1", 0, 0, 1);
  Fill(&b, "v2", 0.5, 1, 1);
  const Comparison c = Compare(StoreSide(a), StoreSide(b), {});
  EXPECT_EQ(Line(c.per_configuration, "s1", "psnr").Verdict(), "undecided");
  const CompareLine& m = Line(c.per_method, "", "psnr");
  EXPECT_TRUE(m.test.over_scenes);
  EXPECT_EQ(m.test.pairs, 2);
  EXPECT_EQ(m.Verdict(), "B better");  // +0.5 on both scenes, no spread
}

// `--metrics nosuch` said the stores had no configuration with a metric in common.
TEST(Compare, AnUnknownMetricIsNamedWithTheKnownOnes) {
  testing::TempDir dir;
  ResultsStore a(dir / "a.db"), b(dir / "b.db");
  Fill(&a, "v1", 0, 0, 1);
  Fill(&b, "v2", 0.5, 1, 1);
  const std::string e = testing::ErrorOf(
      [&] { Compare(StoreSide(a), StoreSide(b), {.metrics = {"psnr", "nosuch"}}); });
  EXPECT_NE(e.find("--metrics nosuch: unknown metric key; the runs of "), std::string::npos) << e;
  EXPECT_NE(e.find(" have: psnr, ssim"), std::string::npos) << e;
  EXPECT_EQ(Compare(StoreSide(a), StoreSide(b), {.metrics = {"all"}}).per_configuration.size(),
            4u);
}

TEST(Compare, TwoCodeVersionsInOneStoreAndTheCommandLine) {
  testing::TempDir dir;
  const fs::path store_path = dir / "one.db";
  {
    ResultsStore store(store_path);
    Fill(&store, "aaaa1111", 0, 0);
    Fill(&store, "bbbb2222", 0.5, 1);  // takes the labels over; the first version's runs keep none
  }
  const ResultsStore store(store_path, false);
  const CompareSide old_side = VersionSide(store, "aaaa");
  EXPECT_EQ(old_side.runs.size(), 6u);  // found again through their identity
  const CompareSide new_side = VersionSide(store, "gbbbb2222");  // by the git description
  const Comparison c = Compare(old_side, new_side, {.metrics = {"psnr"}});
  ASSERT_EQ(c.per_configuration.size(), 2u);
  EXPECT_EQ(Line(c.per_configuration, "s2", "psnr").Verdict(), "B better");
  try {
    VersionSide(store, "cccc");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("aaaa1111 (gaaaa1111-dirty): 6 runs"), std::string::npos)
        << e.what();
  }
  // The command: Markdown on stdout, the files with --out, clear errors.
  const fs::path log = dir / "log.txt", out = dir / "cmp";
  const Command cmd = RunHdr4dArgs({"bench", "compare", store_path.string(), "--versions",
                                    "aaaa,bbbb", "--out", out.string()}, log);
  ASSERT_TRUE(cmd.result.ok()) << cmd.text;
  EXPECT_NE(cmd.text.find("**B better**"), std::string::npos) << cmd.text;
  EXPECT_TRUE(fs::exists(out / "compare.md") && fs::exists(out / "compare.csv"));
  const Command both = RunHdr4dArgs({"bench", "compare", store_path.string()}, log);
  EXPECT_EQ(both.result.exit_code, 1);
  EXPECT_NE(both.text.find("give two stores"), std::string::npos) << both.text;
  const Command csv = RunHdr4dArgs({"bench", "compare", store_path.string(), store_path.string(),
                                    "--format", "csv"}, log);
  ASSERT_TRUE(csv.result.ok()) << csv.text;
  EXPECT_NE(csv.text.find(",same\n"), std::string::npos) << csv.text;  // a store against itself
}

}  // namespace
}  // namespace hdr4d::bench
