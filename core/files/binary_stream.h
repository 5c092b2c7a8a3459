// Raw little-endian binary writing and reading with a running FNV-1a (64-bit) checksum: the one
// format layer of every state file (checkpoints, the Adam state, every tone mapper's state). The
// reader fails with hdr4d::Error naming the source and what it was reading, so a truncated file
// says where it ends.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

namespace hdr4d {

static_assert(std::endian::native == std::endian::little, "state files are little-endian");

// FNV-1a 64-bit offset basis.
inline constexpr std::uint64_t kStateHashSeed = 14695981039346656037ull;

// FNV-1a, 64 bit, continuing from `hash`: enough to detect damage (not tampering), one pass.
std::uint64_t Fnv1a(const void* data, std::size_t size, std::uint64_t hash = kStateHashSeed);

class HashingWriter {
 public:
  explicit HashingWriter(std::ostream& out) : out_(out) {}
  void Bytes(const void* data, std::size_t size);
  template <typename T>
  void Value(T value) {
    Bytes(&value, sizeof(T));
  }
  void ResetHash();
  std::uint64_t hash() const { return hash_; }

 private:
  std::ostream& out_;
  std::uint64_t hash_ = kStateHashSeed;
};

class HashingReader {
 public:
  // `what_file` names the kind of data in messages ("tone mapper state", "Adam state").
  HashingReader(std::istream& in, const std::string& source, const std::string& what_file);
  void Bytes(void* data, std::size_t size, const std::string& what);
  template <typename T>
  T Value(const std::string& what) {
    T value;
    Bytes(&value, sizeof(T), what);
    return value;
  }
  // Reads `count` floats in blocks, so a bogus count in a truncated file fails before it
  // allocates much.
  std::vector<float> Floats(std::uint64_t count, const std::string& what);
  // Reads the stored checksum and fails when it differs from the running one.
  void VerifyChecksum();
  void ResetHash();
  const std::string& source() const { return source_; }
  const std::string& what_file() const { return what_file_; }

 private:
  std::istream& in_;
  std::string source_, what_file_;
  std::uint64_t hash_ = kStateHashSeed;
};

}  // namespace hdr4d
