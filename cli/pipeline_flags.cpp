#include "cli/pipeline_flags.h"

#include <algorithm>

#include <fmt/format.h>

#include "cli/flags.h"
#include "core/util/error.h"

namespace hdr4d::cli {

PipelineFlags::PipelineFlags(CLI::App* cmd, CameraPipelineOptions& options) : options_(options) {
  const std::string group = "Camera pipeline (hidden from training, recorded in synthesis.json)";
  cmd->add_option("--pipeline", options.name,
                  "fixed (the response alone), auto-exposure (a lagged gain that follows the "
                  "brightness), phone (auto-exposure + a tone curve fitted per frame + "
                  "white-balance drift) or rig-mismatch (per-camera gain, response, colour)")
      ->check(OneOf(CameraPipelineNames()))
      ->group(group)
      ->capture_default_str();
  const std::vector<std::string> ae = {"auto-exposure", "phone"};
  const auto add = [&](const char* flag, double& value, const char* help, double min, double max,
                       std::vector<std::string> pipelines) {
    CLI::Option* o = cmd->add_option(flag, value, help)
                         ->check(Real(min, max))
                         ->group(group)
                         ->capture_default_str();
    parameters_.push_back({o, std::move(pipelines)});
  };
  parameters_.push_back(
      {cmd->add_option("--ae-scope", options.ae_scope,
                       "Auto-exposure: rig (one gain per timestamp for every camera) or camera")
           ->check(OneOf({"rig", "camera"}))
           ->group(group)
           ->capture_default_str(),
       ae});
  add("--ae-lag", options.ae_lag,
      "Auto-exposure: time constant of the moving average, in normalised time (0 = none)", 0, 10,
      ae);
  add("--ae-strength", options.ae_strength,
      "Auto-exposure: fraction of a brightness change the gain undoes", 0, 1, ae);
  add("--tone-low", options.tone_low_percentile,
      "Phone: luminance percentile that sets the tone curve's toe", 0, 100, {"phone"});
  add("--tone-high", options.tone_high_percentile,
      "Phone: luminance percentile that sets the tone curve's shoulder (white)", 0, 100,
      {"phone"});
  add("--wb-drift", options.wb_drift, "Phone: amplitude of ln(R gain) = -ln(B gain)", 0, 2,
      {"phone"});
  add("--wb-period", options.wb_period, "Phone: period of the white-balance drift (normalised "
      "time)", 1e-6, 1e6, {"phone"});
  add("--mismatch-gain", options.mismatch_gain,
      "Rig mismatch: per-camera ln gain drawn in [-G, G]", 0, 3, {"rig-mismatch"});
  add("--mismatch-response", options.mismatch_response,
      "Rig mismatch: per-camera response crf(x^e), e in [1-E, 1+E]", 0, 0.5, {"rig-mismatch"});
  add("--mismatch-colour", options.mismatch_colour,
      "Rig mismatch: colour matrix off-diagonals and ln channel gains in [-C, C]", 0, 0.3,
      {"rig-mismatch"});
  add("--vignetting", options.vignetting,
      "Any pipeline: radial falloff 1 - s r^2 (r = 1 in the corners; 0 = none)", 0, 0.99, {});
}

void PipelineFlags::Check() const {
  for (const Parameter& p : parameters_) {
    if (p.option->count() == 0 || p.pipelines.empty()) continue;
    if (std::find(p.pipelines.begin(), p.pipelines.end(), options_.name) == p.pipelines.end())
      Fail("{} applies to --pipeline {} only (this run's is {})", p.option->get_name(),
           fmt::join(p.pipelines, " or "), options_.name);
  }
  options_.Validate();
}

}  // namespace hdr4d::cli
