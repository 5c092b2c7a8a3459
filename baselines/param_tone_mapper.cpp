#include "baselines/param_tone_mapper.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <istream>
#include <ostream>

#include "core/error.h"

namespace hdr4d::baselines {
namespace {

constexpr char kMagic[8] = {'H', 'D', 'R', '4', 'D', 'T', 'M', 'B'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kMaxKindLength = 64;
constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

std::uint64_t Fnv1a(std::uint64_t hash, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * kFnvPrime;
  return hash;
}

// Little-endian is what every supported machine is; the format says so and we check it.
static_assert(std::endian::native == std::endian::little, "the checkpoint format is little-endian");

class HashingWriter {
 public:
  explicit HashingWriter(std::ostream& out) : out_(out) {}
  void Bytes(const void* data, std::size_t size, bool hashed = true) {
    out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (hashed) hash_ = Fnv1a(hash_, data, size);
  }
  template <typename V>
  void Value(const V& v, bool hashed = true) {
    Bytes(&v, sizeof(V), hashed);
  }
  std::uint64_t hash() const { return hash_; }

 private:
  std::ostream& out_;
  std::uint64_t hash_ = kFnvOffset;
};

class HashingReader {
 public:
  HashingReader(std::istream& in, const std::string& source) : in_(in), source_(source) {}
  void Bytes(void* data, std::size_t size, const char* what, bool hashed = true) {
    in_.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
    if (static_cast<std::size_t>(in_.gcount()) != size) {
      Fail("{}: tone mapper state is truncated while reading {}", source_, what);
    }
    if (hashed) hash_ = Fnv1a(hash_, data, size);
  }
  template <typename V>
  V Value(const char* what, bool hashed = true) {
    V v;
    Bytes(&v, sizeof(V), what, hashed);
    return v;
  }
  std::uint64_t hash() const { return hash_; }

 private:
  std::istream& in_;
  const std::string& source_;
  std::uint64_t hash_ = kFnvOffset;
};

}  // namespace

ParamToneMapper::ParamToneMapper(const method::ToneMapperConfig& config,
                                 std::vector<float> initial_params)
    : config_(config), params_(std::move(initial_params)), grads_(params_.size(), 0.f) {}

void ParamToneMapper::BeginFrame(const method::ToneFrame& frame) {
  HDR4D_CHECK(std::isfinite(frame.log_exposure));
  HDR4D_CHECK(frame.image_index >= -1);
  frame_ = frame;
}

void ParamToneMapper::Save(std::ostream& out) const {
  HashingWriter w(out);
  w.Bytes(kMagic, sizeof(kMagic), false);
  w.Value(kVersion, false);
  const auto kind_length = static_cast<std::uint32_t>(config_.kind.size());
  w.Value(kind_length);
  w.Bytes(config_.kind.data(), kind_length);
  w.Value(static_cast<std::uint64_t>(params_.size()));
  w.Bytes(params_.data(), params_.size() * sizeof(float));
  w.Value(w.hash(), false);
}

void ParamToneMapper::Load(std::istream& in, const std::string& source) {
  HashingReader r(in, source);
  char magic[sizeof(kMagic)];
  r.Bytes(magic, sizeof(magic), "the magic word", false);
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) {
    Fail("{}: not a tone mapper state (bad magic; expected \"HDR4DTMB\")", source);
  }
  const auto version = r.Value<std::uint32_t>("the version", false);
  if (version != kVersion) {
    Fail("{}: tone mapper state version {} is not supported (this build reads version {})", source,
         version, kVersion);
  }
  const auto kind_length = r.Value<std::uint32_t>("the kind");
  if (kind_length == 0 || kind_length > kMaxKindLength) {
    Fail("{}: tone mapper state has a kind of length {} (must be 1..{}: corrupt)", source,
         kind_length, kMaxKindLength);
  }
  std::string kind(kind_length, '\0');
  r.Bytes(kind.data(), kind_length, "the kind");
  const auto count = r.Value<std::uint64_t>("the parameter count");
  // Compare the count before reading, so a corrupt count cannot ask for a huge allocation.
  const bool kind_matches = kind == config_.kind;
  if (kind_matches && count != params_.size()) {
    Fail(
        "{}: tone mapper state has {} parameters, this '{}' tone mapper has {} (its "
        "configuration differs)",
        source, count, config_.kind, params_.size());
  }
  if (!kind_matches && count > (std::uint64_t{1} << 28)) {
    Fail("{}: tone mapper state claims {} parameters (corrupt)", source, count);
  }
  std::vector<float> values(count);
  r.Bytes(values.data(), values.size() * sizeof(float), "the parameters");
  const std::uint64_t computed = r.hash();
  const auto stored = r.Value<std::uint64_t>("the checksum", false);
  if (stored != computed) {
    Fail(
        "{}: tone mapper state checksum mismatch (stored {:016x}, computed {:016x}): the data is "
        "corrupt",
        source, stored, computed);
  }
  if (!kind_matches) {
    Fail("{}: tone mapper state is for kind '{}', not '{}'", source, kind, config_.kind);
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      Fail("{}: tone mapper state has a non-finite parameter at index {} ({})", source, i,
           values[i]);
    }
  }
  std::copy(values.begin(), values.end(), params_.begin());
}

}  // namespace hdr4d::baselines
