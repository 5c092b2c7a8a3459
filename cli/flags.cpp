#include "cli/flags.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

namespace hdr4d::cli {

namespace {

// The value as an integer when it is one: optional '-', then digits only.
bool ParseInteger(const std::string& text, std::int64_t* value, bool* overflow) {
  *overflow = false;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  if (begin == end) return false;
  const bool negative = *begin == '-';
  if (!std::all_of(begin + negative, end, [](char c) { return std::isdigit(c) != 0; }) ||
      begin + negative == end) {
    return false;
  }
  const auto [ptr, ec] = std::from_chars(begin, end, *value);
  *overflow = ec == std::errc::result_out_of_range;
  return ptr == end && (ec == std::errc() || *overflow);
}

}  // namespace

CLI::Validator Integer(std::int64_t min, std::int64_t max) {
  const ValueRange range = ValueRange::Integer(min, max);
  const std::string expected = range.Describe();
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        std::int64_t v = 0;
        bool overflow = false;
        if (!ParseInteger(text, &v, &overflow) || overflow || v < min || v > max)
          return fmt::format("expected {}, got '{}'", expected, text);
        return "";
      },
      "INT " + range.Bounds(), "integer");
}

CLI::Validator Seed() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t v = 0;
        const char* end = text.data() + text.size();
        const bool digits = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
          return std::isdigit(static_cast<unsigned char>(c)) != 0;
        });
        const auto [ptr, ec] = std::from_chars(text.data(), end, v);
        if (!digits || ptr != end || ec != std::errc())
          return fmt::format("expected an integer in [0, 2^64 - 1], got '{}'", text);
        return "";
      },
      "UINT64", "seed");
}

CLI::Validator Real(double min, double max, bool open_min) {
  const ValueRange range = ValueRange::Real(min, max, open_min);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        // strtod accepts "nan", "inf" and hex; from_chars the plain decimal forms only.
        double v = 0;
        const char* end = text.data() + text.size();
        const auto [ptr, ec] = std::from_chars(text.data(), end, v);
        if (text.empty() || ptr != end || ec != std::errc() || !range.Contains(v))
          return fmt::format("expected {}, got '{}'", range.Describe(), text);
        return "";
      },
      "NUMBER " + range.Bounds(), "real");
}

CLI::Validator InRange(const ValueRange& range) {
  if (range.integer) {
    // Bounds past int64 (an unbounded range) as int64's own.
    const auto whole = [](double v) {
      constexpr double kLimit = 9.2e18;
      return v >= kLimit    ? std::numeric_limits<std::int64_t>::max()
             : v <= -kLimit ? std::numeric_limits<std::int64_t>::min()
                            : static_cast<std::int64_t>(v);
    };
    return Integer(whole(range.min), whole(range.max));
  }
  return Real(range.min, range.max, range.open_min);
}

CLI::Validator Text(const std::string& what) {
  return CLI::Validator(
      [what](std::string& text) -> std::string {
        if (text.empty()) return fmt::format("expected {}, got an empty value", what);
        return "";
      },
      "", "text");
}

CLI::Validator OneOf(const std::vector<std::string>& names) {
  return CLI::Validator(
      [names](std::string& text) -> std::string {
        if (std::find(names.begin(), names.end(), text) != names.end()) return "";
        return fmt::format("expected one of {}, got '{}'", fmt::join(names, ", "), text);
      },
      fmt::format("{{{}}}", fmt::join(names, ",")), "one-of");
}

CLI::Option* AddExposureUnitOption(CLI::App* cmd, ExposureUnit* unit) {
  return cmd
      ->add_option_function<std::string>(
          "--exposure-unit",
          [unit](const std::string& name) { *unit = ParseExposureUnit(name, "--exposure-unit"); },
          kExposureUnitHelp)
      ->check(
          OneOf({ExposureUnitName(ExposureUnit::kSeconds), ExposureUnitName(ExposureUnit::kStops)}))
      ->default_str(ExposureUnitName(*unit));
}

}  // namespace hdr4d::cli
