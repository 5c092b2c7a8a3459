// hdr4d export-ply: a run's slice at time t as a standard 3DGS .ply for any viewer.
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/util/error.h"
#include "core/files/output_guard.h"
#include "method/run/export_ply.h"
#include "method/run/render_split.h"
#include "method/tonemap/radiance_bank.h"

namespace hdr4d::cli {

void AddExportPlyCommand(CLI::App& app) {
  auto run = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto time = std::make_shared<float>(0.0f);
  CLI::App* cmd = app.add_subcommand(
      "export-ply",
      "Write the 3D Gaussians a trained 4D model shows at normalised time t as a standard 3DGS "
      ".ply (temporal colour folded into SH, marginal into opacity), for any 3DGS viewer.");
  cmd->add_option("--run", *run, "Run folder (from hdr4d train)")
      ->required()
      ->check(Text("a run folder"));
  cmd->add_option("--time,-t", *time, "Normalised time in [0,1]")
      ->check(Real(0, 1))
      ->capture_default_str();
  cmd->add_option("--out,-o", *out, "Output .ply (default RUN/slice_t<t>.ply)")
      ->check(Text("an output .ply file"));
  auto exposure = std::make_shared<double>(0.0);
  cmd->add_option("--exposure", *exposure,
                  "HDR models: display colours at this exposure in seconds (default: the median "
                  "training exposure)")
      ->check(PositiveReal());
  cmd->callback([run, out, time, exposure] {
    const std::string path = out->empty() ? fmt::format("{}/slice_t{:.3f}.ply", *run, *time) : *out;
    method::ProtectRunInputs(*run);
    method::LoadedRun loaded = method::LoadRun(*run);
    CheckOutput(path);
    if (!(*time >= 0 && *time <= 1)) Fail("export-ply: --time {} is outside [0, 1]", *time);
    const double e = *exposure > 0 ? *exposure : method::MedianExposure(loaded.dataset);
    const method::ExportDisplay display{loaded.tone_mapper.get(),
                                        {method::RadianceBank::TimeIndex(*time, loaded.num_times),
                                         -1, static_cast<float>(std::log(e))}};
    const std::size_t n = method::ExportSlicePly(loaded.model, *time, 1.0f, path, &display);
    fmt::print("export-ply: {} Gaussians at t = {} -> {}\n", n, *time, path);
  });
}

}  // namespace hdr4d::cli
