#include "cli/app.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "baselines/tone_mapper_kinds.h"
#include "cli/commands.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/output_guard.h"
#include "core/files/temporary_cleanup.h"
#include "method/raster/simd_dispatch.h"

namespace hdr4d::cli {

namespace {

// One line, however the message was made: library messages may carry newlines.
void PrintError(const std::string& message) {
  std::string line;
  for (char c : message) {
    if (c == '\n') {
      if (!line.empty() && line.back() != ' ') line += "; ";
    } else if (c != '\r') {
      line += c;
    }
  }
  while (!line.empty() && (line.back() == ' ' || line.back() == ';')) line.pop_back();
  std::fflush(stdout);
  std::fprintf(stderr, "hdr4d: error: %s\n", line.c_str());
  std::fflush(stderr);
}

// "train", "dataset check": the subcommands being parsed when the error happened.
std::string CommandPath(const CLI::App& app) {
  std::string path;
  const CLI::App* current = &app;
  for (;;) {
    const std::vector<CLI::App*> subs = current->get_subcommands();
    if (subs.empty()) return path;
    current = subs.front();
    path += (path.empty() ? "" : " ") + current->get_name();
  }
}

std::string LowerFirst(std::string s) {
  if (!s.empty() && s[0] >= 'A' && s[0] <= 'Z' && !(s.size() > 1 && s[1] >= 'A' && s[1] <= 'Z'))
    s[0] = static_cast<char>(s[0] - 'A' + 'a');
  return s;
}

// The option given more often than it takes values, in the subcommands being parsed: CLI11's
// own words for it are "At Most 1 required but received 2".
std::string RepeatedOptionProblem(const CLI::App& app) {
  for (const CLI::App* current = &app;;) {
    for (const CLI::Option* o : current->get_options()) {
      if (o->get_multi_option_policy() != CLI::MultiOptionPolicy::Throw) continue;
      const int takes = std::max(o->get_items_expected_max(), 1);
      const std::size_t got = o->count();
      if (got <= static_cast<std::size_t>(takes)) continue;
      if (takes == 1) return fmt::format("{} was given {} times; give it once", o->get_name(), got);
      return fmt::format("{} takes {} values, got {} (was it given twice?)", o->get_name(), takes,
                         got);
    }
    const std::vector<CLI::App*> subs = current->get_subcommands();
    if (subs.empty()) return "";
    current = subs.front();
  }
}

int ReportParseError(const CLI::App& app, const CLI::ParseError& e) {
  // --help and --version: CLI11 prints them, exit 0.
  if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
  // Thrown by a command that printed its own report (dataset check): only the exit code.
  if (dynamic_cast<const CLI::RuntimeError*>(&e) != nullptr) return e.get_exit_code();
  const std::string command = CommandPath(app);
  if (command.empty()) {
    // "hdr4d trian ...": CLI11 says only that a subcommand is required; name the word instead.
    for (const std::string& word : app.remaining()) {
      if (!word.empty() && word[0] != '-') {
        PrintError(fmt::format("'{}' is not a command (see `hdr4d --help` for the list)", word));
        return 1;
      }
    }
  }
  std::string problem = LowerFirst(e.what());
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr) {
    if (std::string repeated = RepeatedOptionProblem(app); !repeated.empty()) problem = repeated;
  }
  PrintError(fmt::format("{}{} (see `hdr4d {}--help`)", command.empty() ? "" : command + ": ",
                         problem, command.empty() ? "" : command + " "));
  return 1;
}

}  // namespace

std::unique_ptr<CLI::App> MakeApp() {
  // Every tone-mapper kind, the baselines' too, before any flag lists them or a run needs one.
  baselines::RegisterToneMappers();
  auto app =
      std::make_unique<CLI::App>("hdr4d: HDR dynamic novel view synthesis (HDR-4DGS) toolkit");
  // Read when --version prints, after main has applied HDR4D_SIMD_TARGETS.
  app->set_version_flag("--version", [] {
    return "hdr4d 0.1.0; SIMD target: " + method::SimdTargetDescription();
  });
  app->require_subcommand(1);
  app->fallthrough(false);
  auto verbosity = std::make_shared<int>(0);
  app->add_flag("-v,--verbose", *verbosity, "More log output (repeat for debug)");
  app->parse_complete_callback([verbosity] {
    spdlog::set_level(*verbosity >= 2   ? spdlog::level::debug
                      : *verbosity == 1 ? spdlog::level::info
                                        : spdlog::level::warn);
    spdlog::info("SIMD target: {}", method::SimdTargetDescription());
  });
  AddDatasetCommand(*app);
  AddEvalCommand(*app);
  AddSynthLdrCommand(*app);
  AddDemoSceneCommand(*app);
  AddMergeHdrCommand(*app);
  AddGaussianSceneCommand(*app);
  AddTrainCommand(*app);
  AddRenderCommand(*app);
  AddExportPlyCommand(*app);
  AddViewCommand(*app);
  AddToneCurvesCommand(*app);
  AddDatagenCommand(*app);
  AddCalibrateCommand(*app);
  AddBenchCommand(*app);
  return app;
}

int RunApp(CLI::App& app, int argc, char** argv) {
  // The inputs this command reads are protected from its writers for as long as it runs.
  const InputProtectionScope protect_inputs;
  // Symlinks and special files are written through only where the user named them.
  for (int i = 1; i < argc; ++i) NameOnCommandLine(argv[i]);
  // SIGINT, SIGTERM and SIGHUP alike: the temporary files of writes in flight go first.
  RemoveTemporariesOnStopSignals();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return ReportParseError(app, e);
  } catch (const std::bad_alloc&) {
    PrintError("out of memory");
    return 1;
  } catch (const std::exception& e) {
    // hdr4d::Error names the file and the problem; other library exceptions that escaped a
    // check (filesystem, allocation) still end in one line.
    PrintError(e.what());
    return 1;
  }
  return 0;
}

}  // namespace hdr4d::cli
