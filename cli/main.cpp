// `hdr4d`: one binary, one subcommand per job (cli/app.h). A user mistake, bad flags included,
// ends in one line on stderr and exit code 1; only a broken invariant aborts.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "cli/app.h"
#include "method/raster/simd_dispatch.h"

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries results (tables, --json) that other programs parse.
  spdlog::set_default_logger(spdlog::stderr_color_mt("hdr4d"));
  spdlog::set_pattern("%^[%l]%$ %v");
  // HDR4D_SIMD_TARGETS limits the kernels' SIMD targets for the whole run (before any kernel).
  if (!hdr4d::method::ApplySimdTargetsOrPrintError("hdr4d: error: ")) return 1;
  const auto app = hdr4d::cli::MakeApp();
  return hdr4d::cli::RunApp(*app, argc, argv);
}
