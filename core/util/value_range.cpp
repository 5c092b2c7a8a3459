#include "core/util/value_range.h"

#include <fmt/format.h>

#include <cmath>

namespace hdr4d {
namespace {

bool NoUpperBound(const ValueRange& r) {
  if (r.integer) {
    return r.max == static_cast<double>(std::numeric_limits<int>::max()) ||
           r.max >= static_cast<double>(std::numeric_limits<std::int64_t>::max());
  }
  return !(r.max < std::numeric_limits<double>::max());
}

bool NoLowerBound(const ValueRange& r) {
  return r.integer ? r.min <= static_cast<double>(std::numeric_limits<std::int64_t>::min())
                   : !(r.min > std::numeric_limits<double>::lowest());
}

}  // namespace

ValueRange ValueRange::Integer(std::int64_t min, std::int64_t max) {
  return {.integer = true,
          .min = static_cast<double>(min),
          .max = static_cast<double>(max),
          .open_min = false};
}

ValueRange ValueRange::Real(double min, double max, bool open_min) {
  return {.integer = false, .min = min, .max = max, .open_min = open_min};
}

bool ValueRange::Contains(double value) const {
  if (!std::isfinite(value)) return false;
  if (integer && value != std::floor(value)) return false;
  return (open_min ? value > min : value >= min) && value <= max;
}

std::string ValueRange::Bounds() const {
  // Integers print whole (65536, not 6.554e+04); reals in the shortest %g form.
  const auto number = [this](double v) {
    return integer ? fmt::format("{}", static_cast<std::int64_t>(v)) : fmt::format("{:g}", v);
  };
  const bool upper = !NoUpperBound(*this);
  if (NoLowerBound(*this)) return upper ? fmt::format("<= {}", number(max)) : "";
  if (open_min) {
    return upper ? fmt::format("in ({}, {}]", number(min), number(max))
                 : fmt::format("> {}", number(min));
  }
  return upper ? fmt::format("in [{}, {}]", number(min), number(max))
               : fmt::format(">= {}", number(min));
}

std::string ValueRange::Describe() const {
  const std::string bounds = Bounds();
  return fmt::format("{}{}{}", integer ? "an integer" : "a number", bounds.empty() ? "" : " ",
                     bounds);
}

}  // namespace hdr4d
