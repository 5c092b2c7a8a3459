// --exposure-unit on every command that reads a scene (issue 56): a scene whose `exposures` are
// log2 stops (HDR-HexPlane's JSON) trains, renders, resumes, merges and scores exactly as the
// same scene written in seconds, the run records the unit, and a scene read in the wrong unit
// or a run resumed in another is refused in one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using testing::RunHdr4d;

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// A copy of the seconds scene `from` whose JSON files give every exposure as log2 stops.
void WriteStopsCopy(const fs::path& from, const fs::path& to) {
  fs::copy(from, to, fs::copy_options::recursive);
  for (const char* split : {"train", "test", "val"}) {
    const fs::path file = to / (std::string("transforms_") + split + ".json");
    if (!fs::exists(file)) continue;
    json doc = ReadJsonFile(file);
    for (json& frame : doc["frames"])
      frame["exposures"] = std::log2(frame["exposures"].get<double>());
    WriteJsonFile(file, doc);
  }
}

class ExposureUnitCli : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r =
        RunHdr4d("make-demo-scene --out " + seconds_ + " --size 16 --timestamps 2 --cameras 3");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = RunHdr4d("synth-ldr --data " + seconds_ + " --seed 1");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    WriteStopsCopy(seconds_, stops_);
  }
  // A one-line refusal (exit 1) that says `needle`.
  static void ExpectRefused(const std::string& args, const std::string& needle) {
    const testing::CommandResult r = RunHdr4d(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.out << r.err;
    EXPECT_EQ(Lines(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
  }
  testing::TempDir dir_;
  const std::string seconds_ = (dir_ / "seconds").string(), stops_ = (dir_ / "stops").string();
};

TEST_F(ExposureUnitCli, StopsSceneTrainsRendersAndResumesAsItsSecondsTwin) {
  const std::string train = " --iterations 12 --supervision ldr --seed 3 --threads 1";
  // Read in seconds (the default), the stops scene is refused with the fix.
  ExpectRefused("train --data " + stops_ + " --out " + (dir_ / "no").string() + train,
                "--exposure-unit stops");
  EXPECT_FALSE(fs::exists(dir_ / "no" / "config.json"));
  auto r = RunHdr4d("train --data " + seconds_ + " --out " + (dir_ / "a").string() + train);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("train --data " + stops_ + " --out " + (dir_ / "b").string() + train +
               " --exposure-unit stops");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json a = ReadJsonFile(dir_ / "a" / "results.json"),
             b = ReadJsonFile(dir_ / "b" / "results.json");
  // -3, 1, 5 stops are 0.125, 2, 32 s exactly: the same training, bit for bit.
  EXPECT_EQ(a["test"], b["test"]) << a["test"].dump() << "\n" << b["test"].dump();
  EXPECT_EQ(ReadJsonFile(dir_ / "a" / "config.json")["exposure_unit"], "seconds");
  EXPECT_EQ(ReadJsonFile(dir_ / "b" / "config.json")["exposure_unit"], "stops");
  // Render reads the scene in the run's unit (no flag), and draws what the seconds twin draws.
  for (const char* run : {"a", "b"}) {
    r = RunHdr4d("render --run " + (dir_ / run).string() + " --split test");
    ASSERT_EQ(r.exit_code, 0) << run << "\n" << r.err;
  }
  const fs::path png = fs::path("renders") / "test" / "cam02_t001_e0.png";
  ASSERT_TRUE(fs::exists(dir_ / "b" / png));
  EXPECT_EQ(testing::ReadTextFile(dir_ / "a" / png), testing::ReadTextFile(dir_ / "b" / png));
  // --resume keeps the recorded unit; asking for another is refused, the run untouched.
  const std::string checkpoint = testing::ReadTextFile(dir_ / "b" / "checkpoint.bin");
  ExpectRefused(
      "train --out " + (dir_ / "b").string() + " --resume --iterations 14 --exposure-unit seconds",
      "exposure_unit");
  EXPECT_EQ(testing::ReadTextFile(dir_ / "b" / "checkpoint.bin"), checkpoint);
  r = RunHdr4d("train --out " + (dir_ / "b").string() + " --resume --iterations 14 --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadJsonFile(dir_ / "b" / "results.json")["iterations"], 14);
  // A record with a unit that is not one: render names the file and the key.
  json config = ReadJsonFile(dir_ / "a" / "config.json");
  config["exposure_unit"] = "ev";
  WriteJsonFile(dir_ / "a" / "config.json", config);
  ExpectRefused("render --run " + (dir_ / "a").string() + " --split test",
                "config.json: exposure_unit: expected \"seconds\" or \"stops\", got \"ev\"");
}

TEST_F(ExposureUnitCli, SceneCommandsTakeTheUnit) {
  // dataset check / preview, eval --data, merge-hdr --data, synth-ldr --data: the same flag.
  auto r = RunHdr4d("dataset check " + stops_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("--exposure-unit stops"), std::string::npos) << r.out;
  r = RunHdr4d("dataset check --exposure-unit stops --json " + stops_);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(json::parse(r.out)["summary"]["exposure_unit"], "stops");
  r = RunHdr4d("dataset preview --exposure-unit stops " + stops_ + " --out " +
               (dir_ / "p.png").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::string merged_s = (dir_ / "ms").string(), merged_t = (dir_ / "mt").string();
  r = RunHdr4d("merge-hdr --data " + seconds_ + " --out " + merged_s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectRefused("merge-hdr --data " + stops_ + " --out " + merged_t, "--exposure-unit stops");
  r = RunHdr4d("merge-hdr --exposure-unit stops --data " + stops_ + " --out " + merged_t);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& e : fs::directory_iterator(merged_s)) {
    EXPECT_EQ(testing::ReadTextFile(e.path()),
              testing::ReadTextFile(fs::path(merged_t) / e.path().filename()))
        << e.path();
  }
  ExpectRefused("eval " + merged_t + " " + stops_ + "/hdr --data " + stops_,
                "--exposure-unit stops");
  r = RunHdr4d("eval " + merged_t + " " + stops_ + "/hdr --json --exposure-unit stops --data " +
               stops_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(json::parse(r.out)["mean"].contains("mu_psnr_aligned")) << r.out;
  r = RunHdr4d("synth-ldr --data " + stops_ + " --seed 1 --exposure-unit stops");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path ldr = fs::path("images") / "cam00_t000_e0.png";
  ASSERT_TRUE(fs::exists(fs::path(seconds_) / ldr));
  EXPECT_EQ(testing::ReadTextFile(fs::path(seconds_) / ldr),
            testing::ReadTextFile(fs::path(stops_) / ldr));
  ExpectRefused("synth-ldr " + seconds_ + "/hdr/cam00_t000.exr --out " + (dir_ / "x.png").string() +
                    " --exposure-unit stops",
                "--exposure-unit reads a scene's exposures");
  ExpectRefused("dataset check --exposure-unit ev " + stops_, "--exposure-unit");
}

TEST_F(ExposureUnitCli, GridMethodRecordsAndRendersInTheUnit) {
  const std::string run = (dir_ / "hex").string();
  auto r = RunHdr4d(
      "train --method hexplane --data " + stops_ + " --out " + run +
      " --exposure-unit stops --iterations 3 --threads 1 --rays 256 --grid-voxels 4096 8192");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadJsonFile(fs::path(run) / "config.json")["exposure_unit"], "stops");
  r = RunHdr4d("render --run " + run + " --split test");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  ExpectRefused("train --method hexplane --out " + run + " --resume --exposure-unit seconds",
                "--exposure-unit seconds is not the run's");
}

}  // namespace
}  // namespace hdr4d
