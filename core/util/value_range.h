// The numbers a setting accepts, and the one wording every check of it uses: the command line's
// help and errors (cli/flags.h), a training configuration, a run's config.json and the options'
// own Validate all say "expected an integer >= 1, got 0" from the same range.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

namespace hdr4d {

struct ValueRange {
  bool integer = false;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool open_min = false;  // "> min" instead of ">= min"

  // Integers in [min, max]; a max of INT_MAX or INT64_MAX reads as no upper bound (">= min").
  static ValueRange Integer(std::int64_t min, std::int64_t max = std::numeric_limits<int>::max());
  // Finite numbers in [min, max] (or (min, max]); a max of DBL_MAX or more reads as unbounded.
  static ValueRange Real(double min, double max, bool open_min = false);
  // Any finite number.
  static ValueRange AnyReal() { return {}; }

  // Whether a finite `value` is in the range (and whole, for an integer range).
  bool Contains(double value) const;
  // "an integer >= 1", "an integer in [1, 4096]", "a number in [0, 1e+06]", "a number > 0",
  // "a number".
  std::string Describe() const;
  // The bounds alone, as after "INT " or "NUMBER " in a flag's help: ">= 1", "in [0, 1]".
  std::string Bounds() const;
};

}  // namespace hdr4d
