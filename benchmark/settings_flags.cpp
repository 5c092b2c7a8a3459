#include "benchmark/settings_flags.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

bool ValidFlagName(const std::string& name) {
  if (name.empty() || name.front() == '-') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
  });
}

bool IsScalar(const nlohmann::json& v) { return v.is_number() || v.is_string() || v.is_boolean(); }

}  // namespace

std::string FormatNumber(const nlohmann::json& value) {
  if (value.is_number_integer()) return std::to_string(value.get<std::int64_t>());
  if (value.is_number_unsigned()) return std::to_string(value.get<std::uint64_t>());
  return fmt::format("{}", value.get<double>());
}

void ValidateSettings(const nlohmann::json& settings, const std::vector<std::string>& reserved,
                      const std::string& where) {
  if (!settings.is_object()) Fail("{}: settings must be a JSON object of flags", where);
  for (const auto& [key, value] : settings.items()) {
    if (!ValidFlagName(key))
      Fail("{}: '{}' is not a flag name (lower-case letters, digits and '-')", where, key);
    if (std::find(reserved.begin(), reserved.end(), key) != reserved.end())
      Fail("{}: flag '{}' is set by the harness (from the suite's seeds, budgets, supervision or "
           "--jobs), not by settings", where, key);
    if (value.is_null() || IsScalar(value)) {
      if (value.is_number_float() && !std::isfinite(value.get<double>()))
        Fail("{}: flag '{}' must be a finite number", where, key);
      continue;
    }
    if (value.is_array()) {
      if (value.empty() || !std::all_of(value.begin(), value.end(), IsScalar))
        Fail("{}: flag '{}': a list must hold numbers or strings", where, key);
      continue;
    }
    // A fraction from 0 to 1: more would name a step past the run's end (1e300 of it made
    // every run's flag -9223372036854775808).
    if (value.is_object() && value.size() == 1 && value.contains("of_iterations") &&
        value["of_iterations"].is_number() && value["of_iterations"].get<double>() >= 0 &&
        value["of_iterations"].get<double>() <= 1)
      continue;
    Fail("{}: flag '{}': a value is a number, string, true/false, a list, or "
         "{{\"of_iterations\": fraction from 0 to 1}}, not {}", where, key, value.dump());
  }
}

nlohmann::json MergeSettings(const nlohmann::json& base, const nlohmann::json& over) {
  nlohmann::json out = base.is_object() ? base : nlohmann::json::object();
  for (const auto& [key, value] : over.items()) {
    if (value.is_null()) {
      out.erase(key);
    } else {
      out[key] = value;
    }
  }
  return out;
}

std::vector<std::string> SettingsToArgs(const nlohmann::json& settings, std::int64_t iterations,
                                        const std::string& where) {
  std::vector<std::string> args;
  for (const auto& [key, value] : settings.items()) {  // nlohmann::json keeps keys sorted
    const std::string flag = "--" + key;
    if (value.is_null() || (value.is_boolean() && !value.get<bool>())) continue;
    args.push_back(flag);
    if (value.is_boolean()) continue;
    if (value.is_object()) {
      if (iterations <= 0)
        Fail("{}: flag '{}' is a fraction of the iterations, but the budget has none", where, key);
      args.push_back(std::to_string(static_cast<std::int64_t>(
          std::llround(value["of_iterations"].get<double>() * static_cast<double>(iterations)))));
    } else if (value.is_array()) {
      for (const nlohmann::json& v : value)
        args.push_back(v.is_string() ? v.get<std::string>() : FormatNumber(v));
    } else {
      args.push_back(value.is_string() ? value.get<std::string>() : FormatNumber(value));
    }
  }
  return args;
}

}  // namespace hdr4d::bench
