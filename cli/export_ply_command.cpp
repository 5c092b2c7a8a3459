// hdr4d export-ply: a run's slice at time t as a 3DGS .ply (with --hdr, plus the log-radiance
// columns of the HDR extension), or with --dynamic the whole 4D model (docs/hdr-ply.md).
#include <fmt/format.h>

#include <algorithm>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"
#include "method/run/export_ply.h"
#include "method/run/gaussian_4d_ply.h"
#include "method/run/render_split.h"
#include "method/tonemap/radiance_bank.h"

namespace hdr4d::cli {
namespace {

struct ExportFlags {
  std::string run, out;
  float time = 0.0f;
  double exposure = 0.0;
  bool hdr = false, dynamic = false;
};

std::pair<double, double> ExposureRange(const Dataset& d) {
  double lo = 0, hi = 0;
  for (const Frame& f : d.train) {
    lo = lo == 0 ? f.exposure : std::min(lo, f.exposure);
    hi = std::max(hi, f.exposure);
  }
  return {lo, hi};
}

void Export(const ExportFlags& f) {
  const std::string path = !f.out.empty() ? f.out
                           : f.dynamic    ? f.run + "/model_4d.ply"
                                          : fmt::format("{}/slice_t{:.3f}{}.ply", f.run, f.time,
                                                        f.hdr ? "_hdr" : "");
  method::ProtectRunInputs(f.run);
  method::LoadedRun loaded = method::LoadRun(f.run);
  CheckOutputFile(path);
  const bool log_hdr = loaded.model.color_mode == method::ColorMode::kLogHdr;
  if (f.exposure > 0 && !log_hdr) {
    Fail("export-ply: --exposure: run {} ({}) has LDR colours, which do not depend on an exposure",
         f.run, loaded.MethodName());
  }
  if (f.hdr && !log_hdr)
    Fail("export-ply: --hdr: run {} ({}) has LDR colours; there is no HDR to export", f.run,
         loaded.MethodName());
  const auto [e_lo, e_hi] = ExposureRange(loaded.dataset);
  if (f.dynamic) {
    method::Gaussian4dPlyInfo info{1.0f, e_lo, e_hi, loaded.learned_background.value_or(std::vector<float>{}),
                                   loaded.background, loaded.hdr_head.empty() ? nullptr : &loaded.hdr_head};
    const std::size_t n = method::ExportGaussian4dPly(loaded.model, path, info);
    fmt::print("export-ply: {} 4D Gaussians -> {}\n", n, path);
    return;
  }
  if (!(f.time >= 0 && f.time <= 1)) Fail("export-ply: --time {} is outside [0, 1]", f.time);
  const double e = f.exposure > 0 ? f.exposure : method::MedianExposure(loaded.dataset);
  // With --hdr the display columns are secondary: a whole-image mapper (Durand), which cannot map
  // Gaussians, gives way to exposure x radiance as sRGB there instead of refusing the file.
  const bool whole_image = loaded.tone_mapper && !loaded.tone_mapper->pointwise();
  if (f.hdr && whole_image)
    fmt::print("export-ply: the '{}' tone mapper maps whole images; display columns are exposure x "
               "radiance as sRGB\n", loaded.tone_mapper->config().kind);
  const method::ExportDisplay display{f.hdr && whole_image ? nullptr : loaded.tone_mapper.get(),
                                      {method::RadianceBank::TimeIndex(f.time, loaded.num_times),
                                       -1, static_cast<float>(std::log(e))}};
  method::HdrPlyExtension hdr{e_lo, e_hi, loaded.learned_background.value_or(std::vector<float>{}),
                              &loaded.hdr_head};
  const std::size_t n = method::ExportSlicePly(loaded.model, f.time, 1.0f, path, &display,
                                               f.hdr ? &hdr : nullptr);
  fmt::print("export-ply: {} Gaussians at t = {}{} -> {}\n", n, f.time,
             f.hdr ? " with HDR columns" : "", path);
}

}  // namespace

void AddExportPlyCommand(CLI::App& app) {
  auto flags = std::make_shared<ExportFlags>();
  CLI::App* cmd = app.add_subcommand(
      "export-ply",
      "Write the 3D Gaussians a trained model shows at normalised time t as a standard 3DGS .ply "
      "for any 3DGS viewer: temporal colour and marginal folded in at t. LDR-colour models: their "
      "SH coefficients, view dependence included. Log-HDR models: each Gaussian's colour "
      "tone-mapped at --exposure and t (run's tone mapper, else exposure x radiance as sRGB) in "
      "64 directions, fitted with SH of the model's degree (f_dc, f_rest); --hdr adds the exact "
      "log-radiance SH in extra columns. --dynamic writes "
      "the 4D model itself. Layouts: docs/hdr-ply.md");
  cmd->add_option("--run", flags->run, "Run folder (from hdr4d train)")
      ->required()
      ->check(Text("a run folder"));
  cmd->add_option("--time,-t", flags->time, "Normalised time in [0,1]")
      ->check(Real(0, 1))
      ->capture_default_str();
  cmd->add_option("--out,-o", flags->out,
                  "Output .ply (default RUN/slice_t<t>.ply, RUN/slice_t<t>_hdr.ply with --hdr, "
                  "RUN/model_4d.ply with --dynamic)")
      ->check(Text("an output .ply file"));
  cmd->add_option("--exposure", flags->exposure,
                  "Log-HDR models: the display colours' exposure in seconds (default: the median "
                  "training exposure); refused for LDR-colour models")
      ->check(PositiveReal());
  cmd->add_flag("--hdr", flags->hdr,
                "Log-HDR models: add f_hdr_dc_*/f_hdr_rest_*, the SH of log linear radiance "
                "(radiance = exp(0.5 + SH value)), and the scene's exposure range in the header");
  auto* dynamic = cmd->add_flag("--dynamic", flags->dynamic,
                                "Write every 4D Gaussian with its time parameters (the layout "
                                "hdr4d view reads) instead of one slice");
  dynamic->excludes(cmd->get_option("--time"));
  dynamic->excludes(cmd->get_option("--exposure"));
  dynamic->excludes(cmd->get_option("--hdr"));
  cmd->callback([flags] { Export(*flags); });
}

}  // namespace hdr4d::cli
