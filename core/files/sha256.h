// SHA-256 (FIPS 180-4) of bytes and files, as lowercase hex: the checksums of a generated
// dataset's manifest, comparable with `sha256sum`.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace hdr4d {

std::string Sha256Hex(std::string_view bytes);
// Streams the file; throws hdr4d::Error naming it when it cannot be read.
std::string Sha256File(const std::filesystem::path& path);

}  // namespace hdr4d
