// `hdr4d train`'s command line turned into the options to train: the options given (rows of
// train_options_table.h with their values), laid over a --config file or preset, over a resumed
// run's own record or the defaults, with the method's preset of the colour model under the HDR
// options. docs/ARCHITECTURE.md §4 "Options".
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "method/train/train_options_table.h"
#include "method/train/trainer.h"

namespace hdr4d::method {

struct GivenTrainOption {
  const TrainOption* option = nullptr;
  nlohmann::json value;  // of the option's type; a switch: the value it sets
};

struct TrainRequest {
  std::filesystem::path out;  // --out
  bool resume = false;        // --resume
  bool overwrite = false;     // --overwrite
  std::string config;         // --config FILE or preset; empty: none
  std::optional<std::string> method;    // --method, when given
  std::string default_method = "hdr4dgs";  // the method when none is given nor resumed
  // Trained instead on a scene with one exposure and no HDR ground truth when nothing HDR was
  // asked for (TrainOptions::when_nothing_hdr).
  std::string ldr_method = "4dgs";
  std::vector<GivenTrainOption> given;  // the options given, in the table's order

  // Whether the option with this flag was given.
  bool Given(const std::string& flag) const;
};

// The colour model and supervision of a named method (baselines::MethodPreset, which lives
// above method/).
using MethodPresetFn = std::function<HdrTrainingOptions(const std::string& method)>;

// The options to train. Precedence: an option given > the --config file or preset > the
// resumed run's record (--resume; threads excepted: this machine's) > the defaults. The colour
// model is the resumed run's unless --method is given, else the method's preset, with the HDR
// options given laid over it. A new run that asks for nothing HDR (no --method, no tone-mapper,
// supervision or HDR-term option) trains plain 4DGS on a scene with one exposure and no HDR
// ground truth (TrainOptions::when_nothing_hdr). Throws hdr4d::Error for a missing --out or
// --data, a value outside its option's range, a tone-mapper option for a method without one,
// and a combination HdrTrainingOptions::Validate refuses.
TrainOptions ResolveTrainRequest(const TrainRequest& request, const MethodPresetFn& preset);

}  // namespace hdr4d::method
