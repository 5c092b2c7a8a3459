// End-to-end: the hdr4d binary as a user runs it, including its failures.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using testing::RunHdr4d;

int LineCount(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

TEST(Cli, HelpListsEverySubcommand) {
  const auto r = RunHdr4d("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* name : {"dataset", "eval", "synth-ldr", "make-demo-scene", "merge-hdr",
                           "make-gaussian-scene", "train", "render", "export-ply", "view", "bench"}) {
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
    EXPECT_EQ(RunHdr4d(std::string(name) + " --help").exit_code, 0) << name;
  }
  const auto bench = RunHdr4d("bench --help");
  for (const char* name : {"run", "table", "pareto", "report", "stress", "submit", "compare", "slurm",
                           "collect"}) {
    EXPECT_NE(bench.out.find(name), std::string::npos) << name;
    EXPECT_EQ(RunHdr4d(std::string("bench ") + name + " --help").exit_code, 0) << name;
  }
  const auto dataset = RunHdr4d("dataset --help");
  for (const char* name : {"check", "preview"}) {
    EXPECT_NE(dataset.out.find(name), std::string::npos) << name;
    EXPECT_EQ(RunHdr4d(std::string("dataset ") + name + " --help").exit_code, 0) << name;
  }
}

TEST(Cli, NoSubcommandIsAUsageError) {
  const auto r = RunHdr4d("");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("subcommand"), std::string::npos) << r.err;
}

TEST(Cli, UserMistakesEndInOneLineAndExitOne) {
  testing::TempDir dir;
  for (const std::string& args :
       {"eval " + (dir / "missing_pred.png").string() + " " + (dir / "missing_gt.png").string(),
        "synth-ldr " + (dir / "none.exr").string() + " --out " + (dir / "x.png").string(),
        "synth-ldr --data " + (dir / "no_scene").string(),
        "dataset check " + (dir / "no_scene").string(),
        "merge-hdr --data " + (dir / "no_scene").string() + " --out " + (dir / "m").string()}) {
    const auto r = RunHdr4d(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.err;
    if (args.rfind("dataset check", 0) == 0) continue;  // prints a report, not one line
    EXPECT_EQ(LineCount(r.err), 1) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("hdr4d: error: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
  }
}

// HDR4D_SIMD_TARGETS limits the kernels' SIMD target for the whole run; --version and -v say
// which is in use; a name that is not a target is a user mistake like a bad flag.
TEST(Cli, SimdTargetsVariableIsAppliedReportedAndChecked) {
  const auto scalar = testing::RunHdr4dWith("HDR4D_SIMD_TARGETS=Scalar", "--version");
  EXPECT_EQ(scalar.exit_code, 0) << scalar.err;
  EXPECT_NE(scalar.out.find("SIMD target: SCALAR (HDR4D_SIMD_TARGETS=Scalar)"), std::string::npos)
      << scalar.out;
  const auto plain = testing::RunHdr4dWith("env -u HDR4D_SIMD_TARGETS", "--version");
  EXPECT_NE(plain.out.find("SIMD target: "), std::string::npos) << plain.out;
  EXPECT_EQ(plain.out.find("HDR4D_SIMD_TARGETS"), std::string::npos) << plain.out;
  testing::TempDir dir;
  const std::string missing = (dir / "missing.png").string();
  const auto logged =
      testing::RunHdr4dWith("HDR4D_SIMD_TARGETS=scalar", "-v eval " + missing + " " + missing);
  EXPECT_NE(logged.err.find("SIMD target: SCALAR"), std::string::npos) << logged.err;
  const auto bad = testing::RunHdr4dWith("HDR4D_SIMD_TARGETS=sse9", "--version");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(LineCount(bad.err), 1) << bad.err;
  EXPECT_EQ(bad.err.rfind("hdr4d: error: HDR4D_SIMD_TARGETS=sse9: 'sse9' is not", 0), 0u)
      << bad.err;
  EXPECT_NE(bad.err.find("avx2"), std::string::npos) << bad.err;
  EXPECT_TRUE(bad.out.empty()) << bad.out;
}

TEST(Cli, SingleImageSynthesisWritesAnLdrImage) {
  testing::TempDir dir;
  ASSERT_EQ(RunHdr4d("make-demo-scene --out " + (dir / "s").string() +
                     " --size 16 --timestamps 1 --cameras 2 --spp 1")
                .exit_code,
            0);
  const fs::path exr = dir / "s" / "hdr" / "cam00_t000.exr";
  const auto r = RunHdr4d("synth-ldr " + exr.string() + " --exposure 2 --crf srgb --out " +
                          (dir / "a.png").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "a.png"));
  // Zero exposure is refused with a message that says so.
  const auto bad =
      RunHdr4d("synth-ldr " + exr.string() + " --exposure 0 --out " + (dir / "b.png").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("exposure"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "b.png"));
}

// The README's main job at a tiny size: render, synthesise, check, merge, evaluate.
TEST(Cli, DemoPipelineEndToEnd) {
  testing::TempDir dir;
  const std::string scene = (dir / "scene").string();
  auto r =
      RunHdr4d("make-demo-scene --out " + scene + " --size 32 --timestamps 3 --cameras 3 --spp 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("synth-ldr --data " + scene +
               " --crf filmic --full-well 20000 --read-noise 0.002 --seed 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("dataset check " + scene + " --full --json");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto check = nlohmann::json::parse(r.out);
  EXPECT_TRUE(check["ok"].get<bool>());
  r = RunHdr4d("dataset preview " + scene + " --out " + (dir / "preview.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "preview.png"));
  r = RunHdr4d("merge-hdr --data " + scene + " --out " + (dir / "merged").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("eval " + (dir / "merged").string() + " " + scene + "/hdr --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto eval = nlohmann::json::parse(r.out);
  ASSERT_EQ(eval["pairs"].size(), 3u);  // one test camera x 3 timestamps
  EXPECT_GT(eval["mean"]["pu21_psnr"].get<double>(), 30.0) << r.out;
  EXPECT_GT(eval["mean"]["mu_psnr"].get<double>(), 25.0) << r.out;
}

// Train -> render (a split, one time, a video) -> eval -> export-ply, and resume.
TEST(Cli, TrainRenderEvalExport) {
  testing::TempDir dir;
  const std::string scene = (dir / "scene").string(), run = (dir / "run").string();
  auto r = RunHdr4d("make-gaussian-scene --out " + scene +
                    " --size 24 --gaussians 10 --cameras 4 --timestamps 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("train --data " + scene + " --out " + run +
               " --iterations 20 --random-points 300 --seed 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto results = nlohmann::json::parse(testing::ReadTextFile(dir / "run" / "results.json"));
  EXPECT_EQ(results["iterations"], 20);
  EXPECT_TRUE(results["test"].contains("psnr"));
  r = RunHdr4d("train --data " + scene + " --out " + run +
               " --iterations 30 --random-points 300 --seed 2 --resume");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("render --run " + run + " --split test");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "run" / "renders" / "test" / "cam03_t001.png"));
  r = RunHdr4d("eval " + run + "/renders/test " + scene + "/images --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["pairs"].size(), 3u);
  r = RunHdr4d("render --run " + run + " --time 0.3 --camera 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "run" / "renders" / "time" / "test_cam001_t0.3000.png"));
  r = RunHdr4d("render --run " + run + " --video 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "run" / "video" / "frame_0002.png"));
  r = RunHdr4d("export-ply --run " + run + " --time 0.5 --out " + (dir / "slice.ply").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(testing::ReadTextFile(dir / "slice.ply").rfind("ply\nformat binary_little_endian", 0),
            0u);
  // LDR colours have no exposure: --exposure and --hdr are refused, not ignored (issue 56).
  for (const char* flag : {"--exposure 2", "--hdr"}) {
    r = RunHdr4d("export-ply --run " + run + " " + flag + " --out " + (dir / "e.ply").string());
    EXPECT_EQ(r.exit_code, 1) << flag;
    EXPECT_NE(r.err.find("has LDR colours"), std::string::npos) << flag << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "e.ply")) << flag;
  }
  // An HDR head for an LDR-alone run of a scene without HDR truth: refused, the run untouched.
  const std::string ldr_run = (dir / "ldr").string();
  r = RunHdr4d("train --data " + scene + " --out " + ldr_run +
               " --iterations 5 --random-points 300 --supervision ldr");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string checkpoint = testing::ReadTextFile(dir / "ldr" / "checkpoint.bin");
  r = RunHdr4d("train --out " + ldr_run + " --resume --hdr-head");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(LineCount(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--hdr-head fits the HDR output to HDR ground truth"), std::string::npos)
      << r.err;
  EXPECT_EQ(testing::ReadTextFile(dir / "ldr" / "checkpoint.bin"), checkpoint);
  // User mistakes: one line, exit 1.
  for (const std::string& bad :
       {"render --run " + run + " --time 2", "render --run " + run + " --time 0.5 --camera 99",
        "render --run " + (dir / "nope").string(),
        "train --data " + scene + " --out " + (dir / "r2").string() + " --resume"}) {
    r = RunHdr4d(bad);
    EXPECT_EQ(r.exit_code, 1) << bad << "\n" << r.err;
    EXPECT_EQ(LineCount(r.err), 1) << bad << "\n" << r.err;
  }
}

// HDR-4DGS and its baselines from the command line on a small multi-exposure HDR scene: LDR and
// HDR renders that `hdr4d eval` pairs with images/ and hdr/, tone curves, and flag mistakes.
TEST(Cli, HdrMethodsRenderToneCurvesAndFlagErrors) {
  testing::TempDir dir;
  const std::string scene = (dir / "scene").string(), run = (dir / "run").string();
  auto r = RunHdr4d("make-demo-scene --out " + scene + " --size 16 --timestamps 2 --cameras 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("synth-ldr --data " + scene + " --seed 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("train --data " + scene + " --out " + run +
               " --iterations 15 --supervision ldr --context-learner transformer");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto results = nlohmann::json::parse(testing::ReadTextFile(dir / "run" / "results.json"));
  EXPECT_EQ(results["method"], "hdr4dgs");
  EXPECT_TRUE(results["test"].contains("mu_psnr")) << results.dump();
  EXPECT_TRUE(results["test"].contains("psnr")) << results.dump();
  r = RunHdr4d("render --run " + run + " --split test --exposure 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "run" / "renders" / "test" / "cam02_t001_e1.png"));
  EXPECT_TRUE(fs::exists(dir / "run" / "renders" / "test" / "cam02_t001.exr"));
  r = RunHdr4d("eval " + run + "/renders/test " + scene + "/hdr --data " + scene + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto eval = nlohmann::json::parse(r.out);
  EXPECT_EQ(eval["pairs"].size(), 2u);  // 1 test camera x 2 times
  // Training scores the test split one HDR truth at a time (its three brackets together); the
  // same model's renders scored by hdr4d eval must agree, the bracket-aligned metrics included.
  for (const char* key : {"mu_psnr", "mu_psnr_aligned", "hdr_log_slope", "pu21_psnr_aligned"}) {
    EXPECT_NEAR(eval["mean"][key].get<double>(), results["test"][key].get<double>(), 2e-3)
        << key << "\n" << r.out << "\n" << results.dump();
  }
  r = RunHdr4d("tone-curves --run " + run + " --times 0,1 --samples 32");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"tone_curves.csv", "tone_curves.png", "tone_curves.svg"})
    EXPECT_TRUE(fs::exists(dir / "run" / "tone_curves" / f)) << f;
  EXPECT_EQ(LineCount(testing::ReadTextFile(dir / "run" / "tone_curves" / "tone_curves.csv")), 33);
  r = RunHdr4d("export-ply --run " + run + " --time 0.5 --out " + (dir / "hdr.ply").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The finished LDR-alone run takes an HDR head on resume, and becomes an ldr+hdr head run.
  r = RunHdr4d("train --out " + run + " --resume --hdr-head --hdr-head-iterations 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto head_config =
      nlohmann::json::parse(testing::ReadTextFile(dir / "run" / "config.json"));
  EXPECT_EQ(head_config["hdr"]["supervision"], "ldr+hdr");
  EXPECT_EQ(head_config["resolved"]["hdr_head"], true);
  for (const std::string method : {"4dgs-hdr", "hdr-gs"}) {
    r = RunHdr4d("train --data " + scene + " --out " + (dir / method).string() +
                 " --iterations 5 --method " + method);
    EXPECT_EQ(r.exit_code, 0) << method << "\n" << r.err;
  }
  r = RunHdr4d("train --data " + scene + " --out " + (dir / "durand").string() +
               " --iterations 5 --tone-mapper durand --supervision ldr");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("tone-curves --run " + (dir / "durand").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("whole images"), std::string::npos) << r.err;
  // Mistakes: one line naming the problem, exit 1.
  for (const std::string& bad :
       {"train --data " + scene + " --out " + (dir / "x").string() + " --method 3dgs",
        "train --data " + scene + " --out " + (dir / "x").string() + " --tone-mapper aces",
        "train --data " + scene + " --out " + (dir / "x").string() +
            " --method 4dgs --tone-mapper mlp",
        "train --data " + scene + " --out " + (dir / "x").string() + " --supervision hdr-ish",
        "train --data " + scene + " --out " + (dir / "x").string() +
            " --tone-mapper durand --no-pixel-branch",
        "render --run " + run + " --exposure 0", "tone-curves --run " + run + " --times 1.5",
        "tone-curves --run " + (dir / "4dgs-hdr").string()}) {
    r = RunHdr4d(bad);
    EXPECT_EQ(r.exit_code, 1) << bad << "\n" << r.err;
    EXPECT_EQ(LineCount(r.err), 1) << bad << "\n" << r.err;
  }
}

}  // namespace
}  // namespace hdr4d
