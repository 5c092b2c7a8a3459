// Settings objects are passed through to the hdr4d commands as flags, generically, so a new
// `hdr4d train` option (a resolution, a batch size, a preset) is usable from a suite without
// touching the harness:
//   {"densify-grad-threshold": 1e-3}   ->  --densify-grad-threshold 0.001
//   {"no-pixel-branch": true}           ->  --no-pixel-branch      (false or null: nothing)
//   {"exposures": [0.125, 2, 32]}       ->  --exposures 0.125 2 32
//   {"densify-until": {"of_iterations": 0.8333}}  ->  the budget's iterations x 0.8333, rounded
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hdr4d::bench {

// Throws hdr4d::Error naming `where` and the key for a malformed flag name or value, or a flag
// in `reserved` (the ones the harness sets itself).
void ValidateSettings(const nlohmann::json& settings,
                      const std::vector<std::string>& reserved,
                      const std::string& where);

// `over` wins key by key; a null value removes the key.
nlohmann::json MergeSettings(const nlohmann::json& base, const nlohmann::json& over);

// Command-line arguments in key order. `iterations` resolves {"of_iterations": f} (an error
// when the budget has no iteration count).
std::vector<std::string> SettingsToArgs(const nlohmann::json& settings,
                                        std::int64_t iterations,
                                        const std::string& where);

// A number as a command-line argument: integers without a decimal point, others in the
// shortest form that reads back exactly.
std::string FormatNumber(const nlohmann::json& value);

}  // namespace hdr4d::bench
