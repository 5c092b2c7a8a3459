// The whole chain on a rig with known truth: `hdr4d datagen --capture` renders the room for six
// fixed cameras with unlike gains (320x240, six hand-held views, brackets two stops apart),
// `hdr4d calibrate --truth` runs COLMAP, the Ceres refinement, the response recovery, fusion
// and gains on it and compares each with the truth. docs/history/calibration.md has the numbers
// of a larger run with training (benchmark/proofs/capture_proof.sh); the bounds here leave room for
// COLMAP's run-to-run differences.
// Skipped, with the reason, where Blender or COLMAP is not installed.
#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "core/files/json_util.h"
#include "datagen/blender_process.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool HaveBlender() {
  try {
    datagen::FindBlender();
    return true;
  } catch (const Error&) {
    return false;
  }
}

bool HaveColmap() { return std::system("command -v colmap > /dev/null 2>&1") == 0; }

TEST(CaptureProof, DatagenRigCalibratesToItsTruth) {
  if (!HaveBlender()) GTEST_SKIP() << "blender is not installed (bash scripts/install-deps.sh)";
  if (!HaveColmap()) GTEST_SKIP() << "colmap is not installed (bash scripts/install-deps.sh)";
  testing::TempDir dir;
  const testing::CommandResult datagen = testing::RunHdr4d(
      "datagen --capture --scene room --preset mini --width 320 --samples 24 --cameras 6 "
      "--extra-views 6 --frames 2 --brackets 0.5,2,8 --unlike-cameras gains --out '" +
      dir.path().string() + "'");
  ASSERT_EQ(datagen.exit_code, 0) << datagen.err;
  const fs::path capture = dir / "room";
  const testing::CommandResult calibrate = testing::RunHdr4d(
      "calibrate --capture '" + capture.string() + "' --out '" + (dir / "calibrated").string() +
      "' --truth '" + (capture / "truth").string() + "'");
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.err;
  const json c = ReadJsonFile(dir / "calibrated" / "truth_comparison.json");
  SCOPED_TRACE(calibrate.out);
  ASSERT_TRUE(c.contains("geometry")) << c.dump();
  EXPECT_EQ(c["cameras"].size(), 6u);
  EXPECT_LT(c["geometry"]["max_rotation_error_deg"].get<double>(), 0.5);
  EXPECT_LT(c["geometry"]["max_position_error_relative"].get<double>(), 0.015);
  EXPECT_LT(c["geometry"]["max_focal_error_relative"].get<double>(), 0.01);
  for (int ch = 0; ch < 3; ++ch)
    EXPECT_LT(c["response"]["rms_relative_error"][ch].get<double>(), 0.1) << ch;
  EXPECT_LT(c["hdr"]["median_relative_error"].get<double>(), 0.1);
  EXPECT_GT(c["hdr"]["within_10_percent"].get<double>(), 0.5);
  // The unlike cameras were brought into agreement.
  const json report = ReadJsonFile(dir / "calibrated" / "calibration.json");
  EXPECT_LT(report["camera_agreement"]["disagreement_after"].get<double>(),
            report["camera_agreement"]["disagreement_before"].get<double>());
  // And the dataset is one `hdr4d train` reads.
  const testing::CommandResult check =
      testing::RunHdr4d("dataset check '" + (dir / "calibrated").string() + "'");
  EXPECT_EQ(check.exit_code, 0) << check.err;
}

}  // namespace
}  // namespace hdr4d
