// Training configurations (`hdr4d train --config FILE|PRESET`): a flat JSON object of training
// option names and values, from a file or one of the named presets that reproduce the
// reference's per-dataset and per-scene settings (../shared/notes/reference-code-facts.md
// §2.6-2.8). Precedence: a flag given on the command line > the configuration > the defaults
// (whose schedules follow --iterations). docs/ARCHITECTURE.md §4 "Configurations".
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "method/train/trainer.h"

namespace hdr4d::method {

struct TrainPreset {
  std::string name;  // "syn/lego", "real/bed", "dnerf/trex"
  std::string what;  // one line: where the values come from
  nlohmann::json values;
};

// Every preset, in listing order.
const std::vector<TrainPreset>& TrainPresets();

// The keys a configuration may hold, each with the command-line flag that overrides it: the
// rows of the option table with a configuration name (train_options_table.h).
struct TrainConfigKey {
  std::string name;     // as in RUN/config.json's "optimization" ("densify_until")
  std::string flag;     // "--densify-until"; empty when no flag sets it
  std::string accepts;  // "an integer >= 0"
};
const std::vector<TrainConfigKey>& TrainConfigKeys();

// `spec` is a file when something exists at that path, else a preset name; the values as an
// object. Throws hdr4d::Error naming the file and what is wrong with it (a folder or device,
// empty, not JSON, not an object), or the unknown preset (with the list of presets).
nlohmann::json ReadTrainConfig(const std::string& spec);

// Sets `options` from `config` (a JSON object) except the keys whose flag `flag_given` says
// was given. Throws hdr4d::Error "<source>: ..." naming the key for an unknown key, a value of
// the wrong type or out of range (the range the flag's help states).
void ApplyTrainConfig(const nlohmann::json& config,
                      const std::string& source,
                      const std::function<bool(const std::string& flag)>& flag_given,
                      TrainOptions* options);

}  // namespace hdr4d::method
