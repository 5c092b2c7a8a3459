// Issue 51, the second hostile sweep: the hdr4d binary used as a careless or malicious user
// would. Each test names the case of the issue it covers and failed before its fix.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/image/image_io.h"
#include "tests/hostile_scene_fixture.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadTextFile;
using testing::RunHdr4d;
using testing::RunHdr4dWith;

using Sweep = HostileScene;  // tests/hostile_scene_fixture.h: S, R, TrainRun()


// Case 13: an image that is /dev/zero hung eval, dataset check and train forever at 100% CPU;
// a FIFO blocks its reader. Both are refused by name before they are opened.
TEST_F(Sweep, Case13InputsThatAreNotRegularFilesAreRefusedByName) {
  const fs::path image = fs::path(S()) / "images" / "cam00_t000_e0.png";
  fs::remove(image);
  fs::create_symlink("/dev/zero", image);
  const std::string exr = S() + "/hdr/cam00_t000.exr";
  const fs::path fifo = *this / "fifo.exr";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& args :
       {"eval /dev/zero " + exr, "eval " + fifo.string() + " " + exr, "dataset check " + S(),
        "train --data " + S() + " --out " + R() + " --iterations 2 --threads 1"}) {
    const auto r = RunHdr4dWith("timeout 60", args);
    ExpectRefused(r, args, "not a regular file");
  }
  fs::remove(fs::path(S()) / "point3d.ply");
  fs::create_symlink(fifo, fs::path(S()) / "point3d.ply");
  fs::remove(image);
  fs::copy_file(fs::path(S()) / "images" / "cam00_t000_e1.png", image);
  const std::string args = "train --data " + S() + " --out " + R() + " --iterations 2 --threads 1";
  ExpectRefused(RunHdr4dWith("timeout 60", args), args, "FIFO");
}

// Case 14: an RGBA PNG was read premultiplied, so a render with the right RGB at alpha 128
// scored 11 dB although eval ignores alpha.
TEST_F(Sweep, Case14EvalScoresRgbaRendersOnTheirStoredColour) {
  const fs::path gt = fs::path(S()) / "images" / "cam00_t000_e1.png";
  const Image truth = ReadImage(gt);
  ASSERT_EQ(truth.channels(), 3);
  Image rgba(truth.width(), truth.height(), 4, truth.encoding(), 128.0f / 255.0f);
  for (int p = 0; p < truth.width() * truth.height(); ++p)
    for (int c = 0; c < 3; ++c) rgba.data()[p * 4 + c] = truth.data()[p * 3 + c];
  WriteImage(*this / "pred.png", rgba);
  const auto r = RunHdr4d("eval " + (*this / "pred.png").string() + " " + gt.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j.value("identical_pairs", 0), 1) << j.dump();
  EXPECT_DOUBLE_EQ(j["mean"]["ssim"].get<double>(), 1.0) << j.dump();
}

// Case 11: a symlink planted inside --out (`cam03_t000_e0.png -> victim`, `checkpoint.bin ->
// victim`) had its target overwritten. The link is replaced; the victim keeps its bytes.
TEST_F(Sweep, Case11PlantedSymlinksInsideTheOutputAreReplacedNotFollowed) {
  TrainRun();
  testing::WriteTextFile(*this / "victim", "precious");
  const fs::path out = *this / "O";
  fs::create_directories(out);
  fs::create_symlink(*this / "victim", out / "cam03_t000_e0.png");
  auto r = RunHdr4d("render --run " + R() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::is_symlink(out / "cam03_t000_e0.png"));
  EXPECT_EQ(ReadImageSpec(out / "cam03_t000_e0.png").width, 32);
  EXPECT_EQ(ReadTextFile(*this / "victim"), "precious");

  fs::remove_all(R());
  fs::create_directories(R());
  fs::create_symlink(*this / "victim", fs::path(R()) / "checkpoint.bin");
  fs::create_symlink(*this / "victim", fs::path(R()) / "results.json");
  r = RunHdr4d("train --data " + S() + " --out " + R() + " --iterations 5 --threads 1");
  EXPECT_EQ(ReadTextFile(*this / "victim"), "precious") << r.err;
  // A link the user names is still written through, as issue 11 asked.
  fs::create_symlink(*this / "real.json", *this / "named.json");
  r = RunHdr4d("eval " + S() + "/hdr " + S() + "/hdr --out " + (*this / "named.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(*this / "named.json"));
  EXPECT_TRUE(json::parse(ReadTextFile(*this / "real.json")).contains("mean"));
}

// Case 5: `bench stress --out D` emptied an existing D/<case>/ with the user's files in it. Only a
// folder bench stress made (its marker) is emptied; the second run into its own folder works.
TEST_F(Sweep, Case05BenchStressNeverEmptiesAFolderItDidNotMake) {
  const fs::path d = *this / "D";
  const std::string kase = "exposure-1e-4-only";
  fs::create_directories(d / kase);
  testing::WriteTextFile(d / kase / "thesis.tex", "years of work");
  const std::string args = "bench stress --out " + d.string() + " --case " + kase + " --threads 1";
  ExpectRefused(RunHdr4d(args), args, "refusing to empty");
  EXPECT_EQ(ReadTextFile(d / kase / "thesis.tex"), "years of work");
  // A folder bench stress made (its marker) is emptied and used.
  fs::remove(d / kase / "thesis.tex");
  testing::WriteTextFile(d / kase / ".hdr4d-stress-case", "");
  testing::WriteTextFile(d / kase / "stale.txt", "from an earlier run");
  const auto r = RunHdr4d(args);
  EXPECT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_FALSE(fs::exists(d / kase / "stale.txt"));
}

}  // namespace
}  // namespace hdr4d
