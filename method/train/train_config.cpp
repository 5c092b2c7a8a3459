#include "method/train/train_config.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>

#include "core/files/file_access.h"
#include "core/files/json_util.h"
#include "core/util/error.h"
#include "method/train/train_options_table.h"

namespace hdr4d::method {
namespace {

using Json = nlohmann::json;

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
    for (const TrainOption& row : TrainOptionTable()) {
      if (!row.config_name.empty()) k.push_back({row.config_name, row.flag, row.Accepts()});
    }
    return k;
  }();
  return keys;
}

namespace {

// What is at `path` when it is not a regular file: "a folder", "a character device", ...
std::string WhatIsAt(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  switch (status.type()) {
    case std::filesystem::file_type::directory:
      return "a folder";
    case std::filesystem::file_type::character:
      return "a character device";
    case std::filesystem::file_type::block:
      return "a block device";
    case std::filesystem::file_type::fifo:
      return "a FIFO";
    case std::filesystem::file_type::socket:
      return "a socket";
    default:
      return "not a regular file";
  }
}

}  // namespace

Json ReadTrainConfig(const std::string& spec) {
  // A path that exists is the file meant, whatever it is: say what is wrong with it rather than
  // that no preset has its name.
  const PathProbe probe = ProbePath(spec);
  if (probe.kind == PathKind::kUnknown) Fail("--config {}: {}", spec, probe.problem);
  if (probe.kind == PathKind::kFolder || probe.kind == PathKind::kOther) {
    Fail("--config {}: is {}, expected a JSON file of training options or a preset name", spec,
         WhatIsAt(spec));
  }
  if (probe.kind == PathKind::kFile) {
    std::error_code ec;
    if (std::filesystem::file_size(spec, ec) == 0 && !ec) {
      Fail("--config {}: the file is empty, expected a JSON object of training options (`hdr4d "
           "train --list-configs`)",
           spec);
    }
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
    const TrainOption* row = nullptr;
    for (const TrainOption& r : TrainOptionTable())
      if (r.config_name == name) row = &r;
    if (!row) {
      std::vector<std::string> known;
      for (const TrainConfigKey& k : TrainConfigKeys()) known.push_back(k.name);
      Fail("{}: unknown key '{}' (known: {})", source, name, fmt::join(known, ", "));
    }
    // The range a flag states: a configuration is a set of given values.
    if (std::string problem = row->Check(value, /*allow_unset=*/false); !problem.empty())
      Fail("{}: key '{}': {}", source, name, problem);
    if (!row->flag.empty() && flag_given(row->flag)) continue;  // the flag wins
    row->set(options, value);
  }
}

}  // namespace hdr4d::method
