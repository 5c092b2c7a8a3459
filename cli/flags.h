// Checks for every flag that takes a value, run by CLI11 on the text before it is converted: a
// bad value ends in one line naming the flag and what it accepts, before the command does
// anything. Nothing is silently replaced by a default, wrapped (-1 as an unsigned seed) or
// clamped. Every value option of every command carries one of these (cli/app_test.cpp checks
// it), so a new flag cannot skip validation.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <limits>
#include <string>

#include "core/dataset/dataset.h"
#include "core/util/value_range.h"

namespace hdr4d::cli {

// A decimal integer in [min, max] (no sign for min >= 0, no fraction, no exponent).
CLI::Validator Integer(std::int64_t min,
                       std::int64_t max = std::numeric_limits<int>::max());
// A seed: a decimal integer in [0, 2^64 - 1].
CLI::Validator Seed();
// A finite real number in [min, max]; `open_min` excludes min (for "> 0").
CLI::Validator Real(double min, double max, bool open_min = false);
inline CLI::Validator PositiveReal(double max = std::numeric_limits<double>::max()) {
  return Real(0, max, /*open_min=*/true);
}
// A number in `range` (Integer or Real above, with the range's own wording).
CLI::Validator InRange(const ValueRange& range);
// Free text (a path, a name, a spec) that the command checks itself, with the same care: this
// marks the flag as reviewed; it rejects only an empty value.
CLI::Validator Text(const std::string& what);
// One of `names`.
CLI::Validator OneOf(const std::vector<std::string>& names);
// --exposure-unit seconds|stops on a command that reads a scene, setting `unit` (which keeps its
// value when the flag is not given): the same flag, help and check on every such command.
CLI::Option* AddExposureUnitOption(CLI::App* cmd, ExposureUnit* unit);

}  // namespace hdr4d::cli
