#include "core/files/binary_stream.h"

#include <algorithm>

#include "core/util/error.h"

namespace hdr4d {
namespace {

constexpr std::uint64_t kFnvPrime = 1099511628211ull;
constexpr std::size_t kReadBlock = std::size_t{1} << 18;  // floats per read

}  // namespace

std::uint64_t Fnv1a(const void* data, std::size_t size, std::uint64_t hash) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * kFnvPrime;
  return hash;
}

void HashingWriter::Bytes(const void* data, std::size_t size) {
  out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  hash_ = Fnv1a(data, size, hash_);
}

void HashingWriter::ResetHash() { hash_ = kStateHashSeed; }

HashingReader::HashingReader(std::istream& in,
                             const std::string& source,
                             const std::string& what_file)
    : in_(in), source_(source), what_file_(what_file) {}

void HashingReader::Bytes(void* data, std::size_t size, const std::string& what) {
  in_.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
  if (static_cast<std::size_t>(in_.gcount()) != size) {
    Fail("{}: {} is truncated while reading {}", source_, what_file_, what);
  }
  hash_ = Fnv1a(data, size, hash_);
}

std::vector<float> HashingReader::Floats(std::uint64_t count, const std::string& what) {
  std::vector<float> out;
  while (out.size() < count) {
    const std::size_t begin = out.size();
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(kReadBlock, count - begin));
    out.resize(begin + n);
    Bytes(out.data() + begin, n * sizeof(float), what);
  }
  return out;
}

void HashingReader::VerifyChecksum() {
  const std::uint64_t expected = hash_;
  const auto stored = Value<std::uint64_t>("the checksum");
  if (stored != expected) {
    Fail("{}: {} checksum mismatch (stored {:016x}, computed {:016x}): the data is corrupt",
         source_, what_file_, stored, expected);
  }
}

void HashingReader::ResetHash() { hash_ = kStateHashSeed; }

}  // namespace hdr4d
