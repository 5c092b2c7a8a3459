// JSON helpers shared by every reader and writer:
//  - non-finite numbers are not valid JSON, so a PSNR of +inf (identical images) is written as
//    null, never as `inf`;
//  - every parse goes through ParseJson, which refuses nesting deeper than kMaxJsonDepth before
//    nlohmann builds the document (its dump, copy and compare recurse: 60000 nested brackets
//    overflowed the stack);
//  - JsonPreview shows a value in an error message without printing all of it;
//  - JsonField reads typed values and names the file and the key when one is missing or has
//    the wrong type (nlohmann's own type_error names neither).
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "core/files/atomic_file.h"

namespace hdr4d {

inline nlohmann::json FiniteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

// Deeper than any file hdr4d reads or writes (a dataset needs 4 levels), far below the stack.
inline constexpr int kMaxJsonDepth = 256;

// Parses JSON text; throws hdr4d::Error "<source>: invalid JSON: ..." for a syntax error, a
// number out of range, or nesting deeper than kMaxJsonDepth (with its line and column).
nlohmann::json ParseJson(std::string_view text, const std::string& source);

// Parses a JSON file; throws hdr4d::Error naming the file ("file not found", "permission
// denied", the line of a syntax error, ...).
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

// Writes JSON (indented) through WriteFileAtomic: a failed write loses nothing.
void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& value);

// "<type> <text>" of a value, its text cut after about `max_chars` characters ("..."); it never
// prints more than that, however large or deep the value.
std::string JsonPreview(const nlohmann::json& value, std::size_t max_chars = 40);

// A value at `key` (a dotted path for messages, "" for the document) of the JSON in `file`.
// Typed reads throw hdr4d::Error "<file>: key '<key>': expected <type>, got <preview>" or
// "<file>: key '<key>' is missing".
class JsonField {
 public:
  JsonField(const nlohmann::json& value, std::string file, std::string key = "")
      : value_(&value), file_(std::move(file)), key_(std::move(key)) {}

  bool Has(const std::string& name) const;
  JsonField operator[](const std::string& name) const;  // throws when missing
  const nlohmann::json& json() const { return *value_; }

  bool Bool() const;
  double Number() const;  // finite
  std::int64_t Int(std::int64_t min, std::int64_t max) const;
  std::uint64_t Uint64() const;
  std::string String() const;
  JsonField Object() const;  // checks that it is an object
  JsonField Array() const;   // checks that it is an array

  // Absent: the fallback; present with a wrong type: an error as above.
  double NumberOr(const std::string& name, double fallback) const;
  std::int64_t IntOr(const std::string& name,
                     std::int64_t fallback,
                     std::int64_t min,
                     std::int64_t max) const;

  [[noreturn]] void Fail(const std::string& problem) const;  // "<file>: key '<key>': <problem>"

 private:
  const nlohmann::json* value_;
  std::string file_, key_;
};

}  // namespace hdr4d
