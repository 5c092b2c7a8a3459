// hdr4d export-ply: a run's slice at time t as a standard 3DGS .ply for any viewer.
#include <fmt/format.h>

#include "cli/commands.h"
#include "method/export_ply.h"
#include "method/render_run.h"

namespace hdr4d::cli {

void AddExportPlyCommand(CLI::App& app) {
  auto run = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto time = std::make_shared<float>(0.0f);
  CLI::App* cmd = app.add_subcommand(
      "export-ply",
      "Write the 3D Gaussians a trained 4D model shows at normalised time t as a standard 3DGS "
      ".ply (temporal colour folded into SH, marginal into opacity), for any 3DGS viewer.");
  cmd->add_option("--run", *run, "Run folder (from hdr4d train)")->required();
  cmd->add_option("--time,-t", *time, "Normalised time in [0,1]")->capture_default_str();
  cmd->add_option("--out,-o", *out, "Output .ply (default RUN/slice_t<t>.ply)");
  cmd->callback([run, out, time] {
    const std::string path = out->empty() ? fmt::format("{}/slice_t{:.3f}.ply", *run, *time) : *out;
    const std::size_t n = method::ExportSlicePly(method::LoadRunModel(*run), *time, 1.0f, path);
    fmt::print("export-ply: {} Gaussians at t = {} -> {}\n", n, *time, path);
  });
}

}  // namespace hdr4d::cli
