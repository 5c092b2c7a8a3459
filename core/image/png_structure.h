// A PNG file's chunk structure (signature, then chunks of length, type, data and CRC-32 up to
// IEND), checked before libpng reads the file: libpng prints its own "libpng error: ..." line on
// stderr for a truncated or corrupt file before hdr4d can say anything, which broke the promise
// of one line naming the file. With this check those files never reach libpng.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace hdr4d {

// CRC-32 (ISO-HDLC, the one of PNG and zlib) of `size` bytes, continuing from `crc`.
std::uint32_t Crc32(const void* data, std::size_t size, std::uint32_t crc = 0);

// "" when the file is structurally sound, else the problem ("truncated inside chunk IDAT",
// "chunk IDAT fails its CRC", ...). With whole_file false only the signature and the IHDR
// chunk are checked (what reading the header needs).
std::string PngStructureProblem(const std::filesystem::path& path, bool whole_file);

}  // namespace hdr4d
