// The options of `hdr4d train`, one row each, in the spirit of COLMAP's OptionManager: the key
// RUN/config.json records it under, the flag and its help, the values it accepts, whether a
// --config file may set it and a resumed run change it, and the member of TrainOptions it sets
// (whose initialiser is the default). The command line's flags and their help, RUN/config.json
// (written and read back), --config files, `--list-configs`, the resume check and the range
// checks of TrainOptions::Validate are all read from this table: adding an option is one row.
// docs/ARCHITECTURE.md §4 "Options".
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/files/json_util.h"
#include "core/util/value_range.h"
#include "method/train/trainer.h"

namespace hdr4d::method {

// The member's C++ type: a value given as text is converted straight to it (the command line
// does so exactly as CLI11 converts), and RUN/config.json records it with that type.
enum class OptionType { kInt, kInt64, kUint64, kDouble, kFloat, kBool, kText, kJson };

// What a value given on the command line is laid over. kRun: the options (a resumed run's own,
// else the defaults) after any --config. kHdr: the method's preset of the colour model and
// supervision (a resumed run's own unless --method is given). kToneMapper: that preset's tone
// mapper, which the method must have.
enum class OptionTarget { kRun, kHdr, kToneMapper };

// A member value that means "not given" rather than a value of the range: the option then
// follows something else (the run length, the image size, the iterations).
enum class Unset { kNever, kNegative, kZero };

struct TrainOption {
  // Dotted path in RUN/config.json ("optimization.iterations"), the name messages use; empty for
  // a flag that sets several members (--color-lr).
  std::string key;
  std::string flag;      // "--iterations"; empty: no flag sets it
  std::string off_flag;  // a switch's negation ("--no-learn-background"), else empty
  std::string help;
  OptionType type = OptionType::kText;
  ValueRange range;                                    // numbers
  std::function<std::vector<std::string>()> choices;  // text: the values it accepts (unset: any)
  std::string what;                                   // free text: what it names ("a scene folder")
  nlohmann::json switch_value;  // a switch (kBool with a flag): the value its flag sets
  Unset unset = Unset::kNever;
  bool nullable = false;        // null is a value (an unset std::optional member)
  bool show_default = false;    // the help shows the default
  std::string config_name;      // its key in a --config file; empty: not allowed there
  bool may_change_on_resume = false;
  bool from_record = true;  // read back from RUN/config.json (threads: this machine's)
  bool recorded = true;     // written at `key` (false: inside another row's value, or no key)
  // A record without the key (a run from before the option): this value; discarded: an error.
  nlohmann::json if_missing = nlohmann::json(nlohmann::json::value_t::discarded);
  // Given, the run trains what was asked even where a scene has nothing HDR to recover
  // (TrainOptions::when_nothing_hdr).
  bool asks_for_hdr = false;
  // A number that also accepts the word "auto" (--iterations auto), which set() understands.
  bool accepts_auto = false;
  OptionTarget target = OptionTarget::kRun;

  // The member as JSON of its type; null: an unset optional; discarded: not recorded.
  std::function<nlohmann::json(const TrainOptions&)> get;
  // Sets the member(s) from a value that passed Check().
  std::function<void(TrainOptions*, const nlohmann::json&)> set;
  // A given flag, when it means more than set() (its own checks, "auto" keeping the method's).
  std::function<void(TrainOptions*, const nlohmann::json&)> set_given;
  // Reading a record, when it is more than a typed value (the tone mapper's own object).
  std::function<void(TrainOptions*, const JsonField&, const std::string& source)> read;

  // "an integer >= 1", "one of ldr, hdr", "true or false", "a scene folder".
  std::string Accepts() const;
  // "" when `value` is one this option accepts (its type, range or choices), else
  // "expected <Accepts()>, got <value>". allow_unset: the member's "not given" value passes too
  // (a record, the options' own check); a value given by the user must be in the range.
  std::string Check(const nlohmann::json& value, bool allow_unset = true) const;
  // The value a switch's flag (or its negation) sets.
  nlohmann::json SwitchValue(bool off) const;
};

// Every option, in the order of `hdr4d train --help`.
const std::vector<TrainOption>& TrainOptionTable();
// The option with this key or flag (either name of a switch); null when none.
const TrainOption* FindTrainOption(const std::string& key_or_flag);
// Whether a resumed run may change the option recorded at `key` (how long and how fast the run
// goes and how often it reports, not what it learns).
bool MayChangeOnResume(const std::string& key);

// RUN/config.json's record of `options`: every recorded row at its key. `under` ("hdr") gives
// that object alone.
nlohmann::json RecordTrainOptions(const TrainOptions& options, const std::string& under = "");
// Reads a record (RUN/config.json, or its object `under`) into `options`: every row read back,
// type and range checked; errors name `source` and the key.
void ReadTrainOptionsRecord(const nlohmann::json& record,
                            const std::string& source,
                            const std::string& under,
                            TrainOptions* options);
// "" when every option set in `options` (or its object `under`) is within its range or
// choices, else "<key>: expected ..., got ..." for the first that is not. Unset members and
// the tone mapper's fields (ToneMapperConfig::Validate) are left out.
std::string CheckTrainOptionValues(const TrainOptions& options, const std::string& under = "");

}  // namespace hdr4d::method
