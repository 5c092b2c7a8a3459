#include "baselines/param_tone_mapper.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <istream>
#include <ostream>

#include "core/files/binary_stream.h"
#include "core/util/error.h"

namespace hdr4d::baselines {
namespace {

constexpr char kMagic[8] = {'H', 'D', 'R', '4', 'D', 'T', 'M', 'B'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kMaxKindLength = 64;
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
  w.Bytes(kMagic, sizeof(kMagic));
  w.Value(kVersion);
  w.ResetHash();  // the checksum covers what follows the version
  const auto kind_length = static_cast<std::uint32_t>(config_.kind.size());
  w.Value(kind_length);
  w.Bytes(config_.kind.data(), kind_length);
  w.Value(static_cast<std::uint64_t>(params_.size()));
  w.Bytes(params_.data(), params_.size() * sizeof(float));
  w.Value(w.hash());
}

void ParamToneMapper::Load(std::istream& in, const std::string& source) {
  HashingReader r(in, source, "tone mapper state");
  char magic[sizeof(kMagic)];
  r.Bytes(magic, sizeof(magic), "the magic word");
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) {
    Fail("{}: not a tone mapper state (bad magic; expected \"HDR4DTMB\")", source);
  }
  const auto version = r.Value<std::uint32_t>("the version");
  if (version != kVersion) {
    Fail("{}: tone mapper state version {} is not supported (this build reads version {})", source,
         version, kVersion);
  }
  r.ResetHash();  // the checksum covers what follows the version
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
  const std::vector<float> values = r.Floats(count, "the parameters");
  r.VerifyChecksum();
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
