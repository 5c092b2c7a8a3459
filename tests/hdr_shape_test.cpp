// The shape of the HDR that HDR-4DGS learns from LDR brackets alone (issue 12 §2), end to end on
// a Blender-made scene nobody tuned for: datagen's `studio` (a concave Naka-Rushton response, a
// bulb saturated in every bracket that dims over time, a spot light that ramps up, a held-out
// camera lower than the ring of training cameras) at 48 px, 2000 iterations, default flags.
//
// The log-log slope of the held-out HDR against the truth was 0.30 while log-HDR colours learned
// at the reference's 2.5e-3: the tone curve learned one branch per exposure and squeezed the
// HDR. At the log-HDR rate (lr_schedule.h, f_dc_lr_log_hdr) it is 0.69 (BENCHMARKS.md, "Why the
// learned HDR had the wrong shape"); held-out geometry error alone keeps it below 1 here.
#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using testing::RunHdr4d;

bool HaveBlender() {
  return std::getenv("HDR4D_BLENDER") != nullptr ||
         std::system("command -v blender > /dev/null 2>&1") == 0;
}

TEST(HdrShape, LdrTrainingRecoversTheSlopeOfTheTruth) {
  if (!HaveBlender()) GTEST_SKIP() << "blender is not installed (bash scripts/install-deps.sh)";
  testing::TempDir dir;
  auto r = RunHdr4d("datagen --scene studio --preset mini --width 48 --seed 0 --out " +
                    (dir / "data").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunHdr4d("train --data " + (dir / "data" / "studio").string() + " --out " +
               (dir / "run").string() + " --iterations 2000 --supervision ldr --seed 0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto test = nlohmann::json::parse(testing::ReadTextFile(dir / "run" / "results.json"))["test"];
  EXPECT_GT(test["hdr_log_slope"].get<double>(), 0.55) << test.dump();
  EXPECT_GT(test["hdr_log_corr"].get<double>(), 0.75) << test.dump();
  EXPECT_GT(test["psnr"].get<double>(), 20.0) << test.dump();
}

}  // namespace
}  // namespace hdr4d
