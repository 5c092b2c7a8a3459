// JSON helpers shared by every writer of results: non-finite numbers are not valid JSON, so a
// PSNR of +inf (identical images) is written as null, never as `inf`.
#pragma once

#include <cmath>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

namespace hdr4d {

inline nlohmann::json FiniteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

// Parses a JSON file; throws hdr4d::Error naming the file and the line of a syntax error.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

// Writes JSON (indented) through a temporary file and a rename: a failed write loses nothing.
void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& value);

// Writes text the same way.
void WriteTextFileAtomic(const std::filesystem::path& path, const std::string& text);

// Creates the parent folders, lets `write` fill a temporary file next to `path` (binary mode),
// then renames it into place; on any failure the temporary file is removed, `path` keeps what it
// had, and hdr4d::Error names `path`. Every writer of results and checkpoints goes through it.
void WriteFileAtomic(const std::filesystem::path& path,
                     const std::function<void(std::ostream&)>& write);

}  // namespace hdr4d
