#include "core/image/png_structure.h"

#include <fmt/format.h>

#include <array>
#include <cstring>
#include <fstream>
#include <vector>

namespace hdr4d {

namespace {

constexpr std::array<std::uint32_t, 256> MakeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t n = 0; n < 256; ++n) {
    std::uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[n] = c;
  }
  return table;
}

constexpr std::array<std::uint32_t, 256> kCrcTable = MakeCrcTable();

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         std::uint32_t(p[3]);
}

}  // namespace

std::uint32_t Crc32(const void* data, std::size_t size, std::uint32_t crc) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = kCrcTable[(crc ^ bytes[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::string PngStructureProblem(const std::filesystem::path& path, bool whole_file) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot open for reading";
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  unsigned char signature[8] = {};
  if (!in.read(reinterpret_cast<char*>(signature), 8) ||
      std::memcmp(signature, kSignature, 8) != 0) {
    return "not a PNG file (no PNG signature)";
  }
  std::vector<unsigned char> data;
  for (int index = 0;; ++index) {
    unsigned char head[8];
    if (!in.read(reinterpret_cast<char*>(head), 8)) {
      return index == 0 ? "truncated PNG: it ends before the IHDR chunk"
                        : "truncated PNG: it ends before the IEND chunk";
    }
    const std::uint32_t length = BigEndian32(head);
    const std::string type(reinterpret_cast<const char*>(head + 4), 4);
    if (index == 0 && type != "IHDR") return "corrupt PNG: the first chunk is not IHDR";
    if (length > 0x7FFFFFFFu) return fmt::format("corrupt PNG: chunk {} claims {} bytes", type, length);
    data.resize(length + 4);
    if (!in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size())))
      return fmt::format("truncated PNG: it ends inside chunk {} (chunk {})", type, index);
    const std::uint32_t stored = BigEndian32(data.data() + length);
    if (Crc32(data.data(), length, Crc32(head + 4, 4)) != stored)
      return fmt::format("corrupt PNG: chunk {} (chunk {}) fails its CRC check", type, index);
    if (type == "IEND" || !whole_file) return "";
  }
}

}  // namespace hdr4d
