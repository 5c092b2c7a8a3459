#include "core/files/json_util.h"

#include <fstream>
#include <sstream>

#include "core/util/error.h"
#include "core/files/file_access.h"

namespace hdr4d {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Fails when brackets outside strings nest deeper than kMaxJsonDepth. A linear scan: cheaper than
// parsing, and it needs no recursion itself.
void CheckDepth(std::string_view text, const std::string& source) {
  int depth = 0, line = 1;
  std::size_t line_start = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      line_start = i + 1;
    }
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) {
        Fail("{}: invalid JSON: nested deeper than {} levels at line {}, column {}", source,
             kMaxJsonDepth, line, i - line_start + 1);
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

void Preview(const json& value, std::string& out, std::size_t limit) {
  if (out.size() > limit) return;
  if (value.is_array() || value.is_object()) {
    const bool array = value.is_array();
    out += array ? '[' : '{';
    bool first = true;
    for (auto it = value.begin(); it != value.end() && out.size() <= limit; ++it) {
      if (!first) out += ',';
      first = false;
      if (!array) out += json(it.key()).dump() + ':';
      Preview(*it, out, limit);
    }
    out += array ? ']' : '}';
    return;
  }
  out += value.dump();
}

}  // namespace

json ParseJson(std::string_view text, const std::string& source) {
  CheckDepth(text, source);
  try {
    return json::parse(text);
  } catch (const json::exception& e) {  // syntax, or a number out of range
    Fail("{}: invalid JSON: {}", source, e.what());
  }
}

json ReadJsonFile(const fs::path& path) {
  RequireInputFile(path);
  std::ifstream file(path, std::ios::binary);
  if (!file) Fail("{}: cannot open for reading", path.string());
  std::stringstream buffer;
  buffer << file.rdbuf();
  return ParseJson(buffer.str(), path.string());
}

void WriteJsonFile(const fs::path& path, const json& value) {
  WriteTextFileAtomic(path, value.dump(1) + "\n");
}

std::string JsonPreview(const json& value, std::size_t max_chars) {
  std::string text;
  Preview(value, text, max_chars);
  if (text.size() > max_chars) text = text.substr(0, max_chars - 3) + "...";
  return fmt::format("{} {}", value.type_name(), text);
}

void JsonField::Fail(const std::string& problem) const {
  if (key_.empty()) hdr4d::Fail("{}: {}", file_, problem);
  hdr4d::Fail("{}: key '{}': {}", file_, key_, problem);
}

bool JsonField::Has(const std::string& name) const {
  return value_->is_object() && value_->contains(name);
}

JsonField JsonField::operator[](const std::string& name) const {
  const std::string key = key_.empty() ? name : key_ + "." + name;
  if (!value_->is_object()) Object();
  const auto it = value_->find(name);
  if (it == value_->end()) hdr4d::Fail("{}: key '{}' is missing", file_, key);
  return JsonField(*it, file_, key);
}

bool JsonField::Bool() const {
  if (!value_->is_boolean()) Fail("expected true or false, got " + JsonPreview(*value_));
  return value_->get<bool>();
}

double JsonField::Number() const {
  if (!value_->is_number()) Fail("expected a number, got " + JsonPreview(*value_));
  const double v = value_->get<double>();
  if (!std::isfinite(v)) Fail(fmt::format("expected a finite number, got {}", v));
  return v;
}

std::int64_t JsonField::Int(std::int64_t min, std::int64_t max) const {
  const std::string expected = fmt::format("expected an integer in [{}, {}]", min, max);
  if (!value_->is_number()) Fail(expected + ", got " + JsonPreview(*value_));
  if (value_->is_number_unsigned() &&
      value_->get<std::uint64_t>() > static_cast<std::uint64_t>(max)) {
    Fail(expected + ", got " + value_->dump());
  }
  if (value_->is_number_float()) {
    const double d = value_->get<double>();
    if (!(d == std::floor(d) && d >= static_cast<double>(min) && d <= static_cast<double>(max)))
      Fail(expected + ", got " + value_->dump());
    return static_cast<std::int64_t>(d);
  }
  const std::int64_t v = value_->get<std::int64_t>();
  if (v < min || v > max) Fail(expected + ", got " + value_->dump());
  return v;
}

std::uint64_t JsonField::Uint64() const {
  if (value_->is_number_unsigned()) return value_->get<std::uint64_t>();
  if (value_->is_number_integer() && value_->get<std::int64_t>() >= 0)
    return value_->get<std::uint64_t>();
  Fail("expected an integer in [0, 2^64 - 1], got " + JsonPreview(*value_));
}

std::string JsonField::String() const {
  if (!value_->is_string()) Fail("expected a string, got " + JsonPreview(*value_));
  return value_->get<std::string>();
}

JsonField JsonField::Object() const {
  if (!value_->is_object()) Fail("expected an object, got " + JsonPreview(*value_));
  return *this;
}

JsonField JsonField::Array() const {
  if (!value_->is_array()) Fail("expected an array, got " + JsonPreview(*value_));
  return *this;
}

double JsonField::NumberOr(const std::string& name, double fallback) const {
  return Has(name) ? (*this)[name].Number() : fallback;
}

std::int64_t JsonField::IntOr(const std::string& name,
                              std::int64_t fallback,
                              std::int64_t min,
                              std::int64_t max) const {
  return Has(name) ? (*this)[name].Int(min, max) : fallback;
}

}  // namespace hdr4d
