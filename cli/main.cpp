// `hdr4d`: one binary, one subcommand per job. A user mistake ends in one line on stderr and
// exit code 1 (2 for bad command-line syntax); only a broken invariant aborts.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <exception>

#include "cli/commands.h"
#include "core/error.h"

int main(int argc, char** argv) {
  CLI::App app{"hdr4d: HDR dynamic novel view synthesis (HDR-4DGS) toolkit"};
  app.set_version_flag("--version", "hdr4d 0.1.0");
  app.require_subcommand(1);
  app.fallthrough(false);
  int verbosity = 0;
  app.add_flag("-v,--verbose", verbosity, "More log output (repeat for debug)");
  app.parse_complete_callback([&] {
    spdlog::set_level(verbosity >= 2   ? spdlog::level::debug
                      : verbosity == 1 ? spdlog::level::info
                                       : spdlog::level::warn);
  });
  // Logs go to stderr: stdout carries results (tables, --json) that other programs parse.
  spdlog::set_default_logger(spdlog::stderr_color_mt("hdr4d"));
  spdlog::set_pattern("%^[%l]%$ %v");

  hdr4d::cli::AddDatasetCommand(app);
  hdr4d::cli::AddEvalCommand(app);
  hdr4d::cli::AddSynthLdrCommand(app);
  hdr4d::cli::AddDemoSceneCommand(app);
  hdr4d::cli::AddMergeHdrCommand(app);
  hdr4d::cli::AddGaussianSceneCommand(app);
  hdr4d::cli::AddTrainCommand(app);
  hdr4d::cli::AddRenderCommand(app);
  hdr4d::cli::AddExportPlyCommand(app);
  hdr4d::cli::AddToneCurvesCommand(app);
  hdr4d::cli::AddDatagenCommand(app);
  hdr4d::cli::AddCalibrateCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const hdr4d::Error& e) {
    std::fprintf(stderr, "hdr4d: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    // Library exceptions that escaped a check (filesystem, JSON, allocation): still one line.
    std::fprintf(stderr, "hdr4d: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
