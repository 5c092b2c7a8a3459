#include "method/train/train_config.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d::method {
namespace {

using Json = nlohmann::json;

// One key: its flag, whether it takes an integer, its range and where it goes.
struct KeySpec {
  TrainConfigKey key;
  bool integer;
  double min, max;
  std::function<void(TrainOptions*, double)> set;
};

const std::vector<KeySpec>& Specs() {
  constexpr double kIntMax = std::numeric_limits<int>::max();
  using O = TrainOptions;
  auto integer = [](int O::*top) {
    return [top](O* o, double v) { o->*top = static_cast<int>(v); };
  };
  auto opt_int = [](int OptimizationOptions::*f) {
    return [f](O* o, double v) { o->optimization.*f = static_cast<int>(v); };
  };
  auto opt_real = [](double OptimizationOptions::*f) {
    return [f](O* o, double v) { o->optimization.*f = v; };
  };
  static const std::vector<KeySpec> specs = {
      {{"iterations", "--iterations"}, true, 1, kIntMax, opt_int(&OptimizationOptions::iterations)},
      {{"batch_size", "--batch-size"}, true, 1, 4096, opt_int(&OptimizationOptions::batch_size)},
      {{"resolution", "--resolution"}, true, 1, 1 << 16, integer(&O::resolution)},
      {{"max_gaussians", "--max-gaussians"},
       true,
       0,
       1e12,
       [](O* o, double v) { o->optimization.max_gaussians = static_cast<std::int64_t>(v); }},
      {{"densify_from", "--densify-from"}, true, 0, kIntMax,
       opt_int(&OptimizationOptions::densify_from)},
      {{"densify_until", "--densify-until"}, true, 0, kIntMax,
       opt_int(&OptimizationOptions::densify_until)},
      {{"densification_interval", "--densification-interval"}, true, 1, kIntMax,
       opt_int(&OptimizationOptions::densification_interval)},
      {{"densify_grad_threshold", "--densify-grad-threshold"}, false, 1e-30, 1e30,
       opt_real(&OptimizationOptions::densify_grad_threshold)},
      {{"position_lr_init", ""}, false, 1e-30, 1e30,
       opt_real(&OptimizationOptions::position_lr_init)},
      {{"position_lr_final", ""}, false, 1e-30, 1e30,
       opt_real(&OptimizationOptions::position_lr_final)},
      {{"position_lr_max_steps", "--position-lr-steps"}, true, 1, kIntMax,
       opt_int(&OptimizationOptions::position_lr_max_steps)},
      {{"opacity_reset_interval", "--opacity-reset-interval"}, true, 1, kIntMax,
       opt_int(&OptimizationOptions::opacity_reset_interval)},
      {{"sh_increase_interval", "--sh-increase-interval"}, true, 1, kIntMax,
       opt_int(&OptimizationOptions::sh_increase_interval)},
      {{"lambda_dssim", ""}, false, 0, 1, opt_real(&OptimizationOptions::lambda_dssim)},
  };
  return specs;
}

// HDR-4DGS's configs/HDR-4D-Syn/<scene>.yaml: 20000 iterations at resolution 2, batch 1,
// densify every 200 (tank 100) until 15000 (hook, jump 18000; standup 16000), the position
// learning rate decaying over the densification window.
TrainPreset Syn(const std::string& scene, int interval, int until) {
  return {"syn/" + scene,
          fmt::format("HDR-4D-Syn {}: HDR-4DGS config (res 2, batch 1, densify every {} until {})",
                      scene, interval, until),
          Json{{"iterations", 20000},
               {"resolution", 2},
               {"batch_size", 1},
               {"densification_interval", interval},
               {"densify_until", until},
               {"position_lr_max_steps", until}}};
}

// configs/HDR-4D-Real/<scene>.yaml: 20000 iterations at resolution 4, batch 4, densify until
// 10000 (bed, excavator) or 15000 with at most 2M Gaussians (tank, toys); bed's position
// learning rate is 10x the default.
TrainPreset Real(const std::string& scene, int until, std::int64_t max_gaussians) {
  Json v{{"iterations", 20000}, {"resolution", 4}, {"batch_size", 4}, {"densify_until", until}};
  std::string what = fmt::format("HDR-4D-Real {}: HDR-4DGS config (res 4, batch 4, densify until {}",
                                 scene, until);
  if (max_gaussians > 0) {
    v["max_gaussians"] = max_gaussians;
    what += fmt::format(", at most {} Gaussians", max_gaussians);
  }
  if (scene == "bed") {
    v["position_lr_init"] = 0.0016;
    v["position_lr_final"] = 1.6e-5;
    what += ", position lr 1.6e-3 -> 1.6e-5";
  }
  return {"real/" + scene, what + ")", v};
}

// 4DGS's configs/dnerf/<scene>.yaml (train with --method 4dgs): 30000 iterations (bouncingballs
// 20000) at resolution 2, the scene's batch size, densify every 100 until 15000 (bouncingballs
// 10000).
TrainPreset DNerf(const std::string& scene, int batch) {
  const bool balls = scene == "bouncingballs";
  const int iterations = balls ? 20000 : 30000, until = balls ? 10000 : 15000;
  return {"dnerf/" + scene,
          fmt::format("D-NeRF {}: 4DGS config (res 2, batch {}, {} iterations, densify every 100 "
                      "until {}; use --method 4dgs)",
                      scene, batch, iterations, until),
          Json{{"iterations", iterations},
               {"resolution", 2},
               {"batch_size", batch},
               {"densification_interval", 100},
               {"densify_until", until}}};
}

}  // namespace

const std::vector<TrainPreset>& TrainPresets() {
  static const std::vector<TrainPreset> presets = [] {
    std::vector<TrainPreset> p;
    for (const char* scene : {"airplane", "deer", "lego", "mutant"}) p.push_back(Syn(scene, 200, 15000));
    p.push_back(Syn("tank", 100, 15000));
    p.push_back(Syn("hook", 200, 18000));
    p.push_back(Syn("jump", 200, 18000));
    p.push_back(Syn("standup", 200, 16000));
    p.push_back(Real("bed", 10000, 0));
    p.push_back(Real("excavator", 10000, 0));
    p.push_back(Real("tank", 15000, 2'000'000));
    p.push_back(Real("toys", 15000, 2'000'000));
    for (const auto& [scene, batch] : std::vector<std::pair<const char*, int>>{
             {"lego", 2}, {"bouncingballs", 2}, {"hellwarrior", 1}, {"hook", 8}, {"mutant", 8},
             {"standup", 8}, {"jumpingjacks", 16}, {"trex", 24}})
      p.push_back(DNerf(scene, batch));
    return p;
  }();
  return presets;
}

const std::vector<TrainConfigKey>& TrainConfigKeys() {
  static const std::vector<TrainConfigKey> keys = [] {
    std::vector<TrainConfigKey> k;
    for (const KeySpec& s : Specs()) k.push_back(s.key);
    return k;
  }();
  return keys;
}

Json ReadTrainConfig(const std::string& spec) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(spec, ec)) {
    Json j = ReadJsonFile(spec);
    if (!j.is_object())
      Fail("{}: a training configuration must be a JSON object of option names and values", spec);
    return j;
  }
  std::vector<std::string> names;
  for (const TrainPreset& p : TrainPresets()) {
    if (p.name == spec) return p.values;
    names.push_back(p.name);
  }
  Fail("--config {}: no such file and no such preset (presets: {}; `hdr4d train --list-configs`)",
       spec, fmt::join(names, ", "));
}

void ApplyTrainConfig(const Json& config,
                      const std::string& source,
                      const std::function<bool(const std::string& flag)>& flag_given,
                      TrainOptions* options) {
  if (!config.is_object()) Fail("{}: a training configuration must be a JSON object", source);
  for (const auto& [name, value] : config.items()) {
    const KeySpec* spec = nullptr;
    for (const KeySpec& s : Specs())
      if (s.key.name == name) spec = &s;
    if (!spec) {
      std::vector<std::string> known;
      for (const KeySpec& s : Specs()) known.push_back(s.key.name);
      Fail("{}: unknown key '{}' (known: {})", source, name, fmt::join(known, ", "));
    }
    const bool ok = value.is_number() && (spec->integer ? value.is_number_integer()
                                                        : std::isfinite(value.get<double>()));
    if (!ok) {
      Fail("{}: key '{}': expected {}, got {}", source, name,
           spec->integer ? "an integer" : "a number", value.dump());
    }
    const double v = value.get<double>();
    if (v < spec->min || v > spec->max) {
      Fail("{}: key '{}': {} is out of range [{:g}, {:g}]", source, name, value.dump(), spec->min,
           spec->max);
    }
    if (!spec->key.flag.empty() && flag_given(spec->key.flag)) continue;  // the flag wins
    spec->set(options, v);
  }
}

}  // namespace hdr4d::method
