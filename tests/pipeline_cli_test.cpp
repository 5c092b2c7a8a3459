// End-to-end: `synth-ldr --data --pipeline` as a user runs it, and its mistakes.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/testing.h"

namespace hdr4d {
namespace {
using testing::RunHdr4d;

TEST(PipelineCli, PhoneRecordsItsParametersAndMistakesAreRefused) {
  testing::TempDir dir;
  const std::string scene = (dir / "scene").string();
  auto r =
      RunHdr4d("make-demo-scene --out " + scene + " --size 24 --timestamps 3 --cameras 2 --spp 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("synth-ldr --data " + scene + " --pipeline phone --wb-drift 0.2 --ae-lag 0.3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "scene" / "synthesis.json");
  const nlohmann::json record = nlohmann::json::parse(in)["pipeline"];
  EXPECT_EQ(record["name"], "phone");
  EXPECT_EQ(record["white_balance_drift"]["amplitude"], 0.2);
  EXPECT_EQ(record["auto_exposure"]["lag"], 0.3);
  EXPECT_EQ(record["views"].size(), 6u);
  r = RunHdr4d("dataset check " + scene + " --full");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;

  // A parameter of another pipeline, a pipeline in single-image mode, an unknown name.
  r = RunHdr4d("synth-ldr --data " + scene + " --wb-drift 0.2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--wb-drift applies to --pipeline phone only"), std::string::npos) << r.err;
  r = RunHdr4d("synth-ldr " + scene + "/hdr/x.exr --out " + (dir / "x.png").string() +
               " --pipeline auto-exposure");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("need --data"), std::string::npos) << r.err;
  r = RunHdr4d("synth-ldr --data " + scene + " --pipeline iphone");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("iphone"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace hdr4d
