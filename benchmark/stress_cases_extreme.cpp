// The stress cases with extreme inputs: exposures from 1e-4 to 1e3 s, radiance scaled by 1e-6
// and 1e6 (benchmark/stress.h lists every category).
#include <fmt/format.h>

#include <cmath>

#include "benchmark/scoring.h"
#include "benchmark/stress_cases.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "method/train/checkpoint.h"

namespace hdr4d::bench::stress {
namespace fs = std::filesystem;

void AddExtremeExposureCases(std::vector<Case>& cases) {
  AddCase(cases, "exposure-bracket-1e-4-to-1e3", "extreme exposure",
          "LDR at 1e-4, 1 and 1e3 s (black to white); HDR-4DGS from LDR only", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {"--exposures", "0.0001,1,1000"});
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
  AddCase(cases, "exposure-1e-4-only", "extreme exposure",
          "every LDR image at 1e-4 s (nearly black)", [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {"--exposures", "0.0001"});
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
  AddCase(cases, "exposure-1e3-only", "extreme exposure", "every LDR image at 1e3 s (nearly white)",
          [](const Ctx& c) {
            MakeScene(c, c.dir / "scene", {"--exposures", "1000"});
            return TrainRenderScore(c, c.dir / "scene", {"--supervision", "ldr"});
          });
}

// A converged model sits at the scene's radiance scale; 150 iterations do not get there (the
// log-HDR colours start near radiance 1, see the detail line), so the trained model's log
// radiance is shifted by log(k) before rendering: renders at 1e-6 and 1e6, scored against
// ground truth at that scale.
static StressOutcome RadianceCase(const Ctx& c, double k) {
  const fs::path scene = c.dir / "scene";
  MakeScene(c, c.dir / "unit", {});
  MakeScene(c, scene, {}, false);
  ScaleRadiance(scene, k);
  const Exec s = Hdr4d(c, {"synth-ldr", "--data", scene.string(), "--crf", "filmic", "--full-well",
                           "20000", "--read-noise", "0.002", "--seed", "1"});
  if (!s.r.ok()) Fail("synth-ldr: {}", s.r.Describe());
  // The same training at unit scale, for the detail line.
  const Exec unit =
      Hdr4d(c, TrainArgs(c, c.dir / "unit", c.dir / "unit_run", {"--supervision", "ldr+hdr"}));
  const Exec t = Hdr4d(c, TrainArgs(c, scene, c.dir / "trained", {"--supervision", "ldr+hdr"}));
  StressOutcome o;
  o.checks[kNoCrash] = NoCrash(t.r);
  o.checks[kNoNaN] = false;
  if (!t.r.ok() || !unit.r.ok()) {
    o.detail = "train: " + Short(t);
    return o;
  }
  const double psnr = ReadJsonFile(c.dir / "trained" / "results.json")["test"].value("psnr", NAN);
  const double unit_psnr =
      ReadJsonFile(c.dir / "unit_run" / "results.json")["test"].value("psnr", NAN);
  method::Checkpoint ck = method::LoadCheckpoint(c.dir / "trained" / "checkpoint.bin");
  for (float& v : ck.model.color_dc) v += static_cast<float>(std::log(k) / method::kShC0);
  {
    const RunFolderWriter writer(c.dir / "trained");  // this case edits the trained model on purpose
    method::SaveCheckpoint(c.dir / "trained" / "checkpoint.bin", ck);
  }
  const Exec r = Hdr4d(c, {"render", "--run", (c.dir / "trained").string(), "--split", "test",
                           "--out", (c.dir / "renders").string()});
  o.checks[kNoCrash] = NoCrash(t.r) && NoCrash(r.r);
  if (!r.r.ok()) {
    o.detail = "render: " + Short(r);
    return o;
  }
  double max = 0;
  std::string bad;
  try {
    for (const auto& e : fs::directory_iterator(c.dir / "renders"))
      if (e.path().extension() == ".exr")
        max = std::max<double>(max, ReadImage(e.path()).MaxValue());
    const ScoredRenders sc =
        ScoreRenders(LoadDataset(scene, {.image_check = ImageCheck::kNone}), c.dir / "renders", {});
    for (const FrameResult& f : sc.frames)
      for (const auto& [key, v] : f.metrics)
        if (std::isnan(v)) bad = f.frame + ":" + key;
  } catch (const Error& e) {
    bad = e.what();
  }
  o.checks[kNoNaN] = bad.empty();
  o.detail = bad.empty() ? fmt::format(
                               "HDR renders up to {:.3g}, all scores finite. Quality, not a "
                               "numerical failure: LDR PSNR {:.1f} dB after 150 iterations "
                               "against {:.1f} dB at unit scale, because the log-HDR colours "
                               "start near radiance 1 and the colour learning rate moves them "
                               "slowly toward log({:g})",
                               max, psnr, unit_psnr, k)
                         : "not finite: " + bad;
  return o;
}

void AddExtremeRadianceCases(std::vector<Case>& cases) {
  AddCase(
      cases, "radiance-1e-6", "extreme radiance",
      "HDR ground truth scaled by 1e-6 (exposures by 1e6), LDR+HDR supervision, renders at 1e-6",
      [](const Ctx& c) { return RadianceCase(c, 1e-6); });
  AddCase(cases, "radiance-1e6", "extreme radiance",
          "HDR ground truth scaled by 1e6 (exposures by 1e-6), LDR+HDR supervision, renders at 1e6",
          [](const Ctx& c) { return RadianceCase(c, 1e6); });
}

}  // namespace hdr4d::bench::stress
