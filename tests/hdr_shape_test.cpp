// The shape of the HDR that HDR-4DGS learns from LDR brackets alone (issue 12 §2), end to end on
// a Blender-made scene nobody tuned for: datagen's `studio` (a concave Naka-Rushton response, a
// bulb saturated in every bracket that dims over time, a spot light that ramps up, a held-out
// camera lower than the ring of training cameras) at 48 px, 2000 iterations, default flags.
//
// The log-log slope of the held-out HDR against the truth was 0.30 while log-HDR colours learned
// at the reference's 2.5e-3: the tone curve learned one branch per exposure and squeezed the
// HDR. At the log-HDR rate (lr_schedule.h, f_dc_lr_log_hdr) it is 0.69 (docs/history/accuracy.md,
// "Why the learned HDR had the wrong shape"); held-out geometry error alone keeps it below 1 here.
// The log correlation counts the held-out camera's holes (measured pixels the model renders
// black) since the metric stopped dropping them (core/metrics/hdr_alignment.h): 0.70 on the 2026-11-27
// host with the fixed background of the time, where dropping them gave more than 0.75; hence
// 0.5, with room for the host spread and the learned background, the default since (the slope
// check is what catches a squeezed HDR).
//
// Adding HDR supervision must not wreck the held-out LDR (issue 12 §3). It did while the pixel
// branch took log(HDR + 1e-5) in the HDR target's units, where this scene's darkest recorded
// pixels sit, and while log colours started 10^3x too bright for the HDR term (with the pixel
// branch alone: 12.5 against 25.3 dB on standup). One run cannot hold it to "no worse": on
// studio LDR+HDR is 0.49 dB below LDR alone on average with a per-seed spread of about 0.6 dB
// (8 seeds, docs/history/accuracy.md, "A scale-invariant HDR term"), and which seed is unlucky
// depends on the host as well (likely the SIMD kernels' per-CPU rounding): on one host this run
// gave 21.69 against 21.50 dB, on the 2026-11-26 sixth-pass host 19.67 against 21.42, with the same
// code. So the test guards against a collapse (more than 3 dB) and checks that the HDR term shows
// in the HDR.
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

void MakeStudio(const fs::path& data) {
  const auto r = RunHdr4d("datagen --scene studio --preset mini --width 48 --seed 0 --out " +
                          data.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

// Trains 2000 iterations with default flags and the given supervision; the held-out metrics.
nlohmann::json TrainStudio(const fs::path& data, const fs::path& run,
                           const std::string& supervision) {
  const auto r = RunHdr4d("train --data " + (data / "studio").string() + " --out " +
                          run.string() + " --iterations 2000 --supervision " + supervision +
                          " --seed 0");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return {};
  return nlohmann::json::parse(testing::ReadTextFile(run / "results.json"))["test"];
}

TEST(HdrShape, LdrTrainingRecoversTheSlopeOfTheTruth) {
  if (!HaveBlender()) GTEST_SKIP() << "blender is not installed (bash scripts/install-deps.sh)";
  testing::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(MakeStudio(dir / "data"));
  const auto test = TrainStudio(dir / "data", dir / "run", "ldr");
  ASSERT_FALSE(test.is_null());
  EXPECT_GT(test["hdr_log_slope"].get<double>(), 0.55) << test.dump();
  // Where the held-out LDR is reproduced the geometry is right, and the slope is the tone curve's
  // alone (core/metrics/hdr_alignment.h): 0.84 here on the 2026-11-28 host (0.93 at 96 px and 3000
  // iterations), 0.17 with the reference's colour rate (a squeezed HDR behind the LDR).
  EXPECT_GT(test["hdr_log_slope_ldr_fit"].get<double>(), 0.7) << test.dump();
  EXPECT_LT(test["hdr_log_slope_ldr_fit"].get<double>(), 1.3) << test.dump();
  EXPECT_GT(test["hdr_log_corr"].get<double>(), 0.5) << test.dump();
  EXPECT_GT(test["psnr"].get<double>(), 20.0) << test.dump();
}

TEST(HdrShape, HdrSupervisionDoesNotCollapseTheHeldOutLdr) {
  if (!HaveBlender()) GTEST_SKIP() << "blender is not installed (bash scripts/install-deps.sh)";
  testing::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(MakeStudio(dir / "data"));
  const auto ldr = TrainStudio(dir / "data", dir / "ldr", "ldr");
  const auto both = TrainStudio(dir / "data", dir / "both", "ldr+hdr");
  ASSERT_FALSE(ldr.is_null() || both.is_null());
  const double psnr = ldr["psnr"].get<double>(), mu = ldr["mu_psnr"].get<double>();
  EXPECT_GT(both["psnr"].get<double>(), psnr - 3.0) << both.dump() << "\nLDR only: " << ldr.dump();
  // The HDR term must show in the HDR: the reference's own-maximum protocol, well above LDR alone.
  EXPECT_GT(both["mu_psnr"].get<double>(), mu + 3.0) << both.dump() << "\nLDR only: " << mu;
}

}  // namespace
}  // namespace hdr4d
