// hdr4d tone-curves: the learned tone curves of a run per channel at chosen times (paper Fig. 3).
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/flags.h"
#include "method/run/render_split.h"
#include "method/run/tone_curve_report.h"

namespace hdr4d::cli {

void AddToneCurvesCommand(CLI::App& app) {
  auto options = std::make_shared<method::ToneCurvesOptions>();
  auto run = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "tone-curves",
      "Write a run's learned tone curves (LDR value against log radiance + log exposure, per "
      "channel, one line per time) as CSV, PNG and SVG: how the Dynamic Tone Mapper adapts to "
      "the scene's radiance over time.");
  cmd->add_option("--run", *run, "Run folder (from hdr4d train)")
      ->required()
      ->check(Text("a run folder"));
  cmd->add_option("--out", *out, "Output folder (default RUN/tone_curves)")
      ->check(Text("an output folder"));
  cmd->add_option("--times", options->times, "Normalised times in [0,1]")
      ->delimiter(',')
      ->check(Real(0, 1))
      ->capture_default_str();
  cmd->add_option("--x-min", options->x_min, "Smallest log radiance + log exposure")
      ->check(Real(-1000, 1000))
      ->capture_default_str();
  cmd->add_option("--x-max", options->x_max, "Largest log radiance + log exposure")
      ->check(Real(-1000, 1000))
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Samples per curve")
      ->check(Integer(2, 100000))
      ->capture_default_str();
  cmd->callback([options, run, out] {
    options->run = *run;
    options->out = *out;
    method::ProtectRunInputs(*run);
    for (const auto& path : method::WriteToneCurves(*options))
      fmt::print("tone-curves: {}\n", path.string());
  });
}

}  // namespace hdr4d::cli
