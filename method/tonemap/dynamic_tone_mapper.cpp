#include "method/tonemap/dynamic_tone_mapper.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <istream>
#include <ostream>

#include "core/util/error.h"
#include "core/files/binary_stream.h"

namespace hdr4d::method {
namespace {

constexpr char kDtmMagic[8] = {'H', 'D', 'R', '4', 'D', 'D', 'T', 'M'};
constexpr std::uint32_t kDtmVersion = 2;  // 2: the bank's written flags
constexpr std::uint32_t kMaxConfigBytes = 1u << 20;

const ToneMapperConfig& Checked(const ToneMapperConfig& config) {
  const std::string problem = config.Validate();
  if (!problem.empty()) Fail("Dynamic Tone Mapper: invalid configuration: {}", problem);
  if (config.kind != "dtm") {
    Fail("Dynamic Tone Mapper: configuration kind is '{}', expected 'dtm'", config.kind);
  }
  return config;
}

}  // namespace

DynamicToneMapper::DynamicToneMapper(const ToneMapperConfig& config)
    : config_(Checked(config)),
      core_(DtmShape::FromConfig(config_)),
      bank_(config_.num_times),
      params_(core_.shape().NumParams()),
      grads_(params_.size(), 0.0f) {
  core_.Init(config_.seed, params_.data());
  window_.reserve(std::size_t(config_.context_window) * RadianceBank::kColumns);
}

void DynamicToneMapper::CheckTimeIndex(int time_index, const char* what) const {
  if (time_index < 0 || time_index >= bank_.size()) {
    Fail("Dynamic Tone Mapper: {} time index {} is outside the radiance bank's {} rows (0..{})",
         what, time_index, bank_.size(), bank_.size() - 1);
  }
}

void DynamicToneMapper::BeginFrame(const ToneFrame& frame) {
  CheckTimeIndex(frame.time_index, "view");
  if (!std::isfinite(frame.log_exposure)) {
    Fail("Dynamic Tone Mapper: the view's log exposure is not finite ({})", frame.log_exposure);
  }
  HDR4D_CHECK(params_.size() == core_.shape().NumParams() && grads_.size() == params_.size());
  if (core_.has_pending_gradient()) core_.EndFrameBackward(grads_.data());
  const int length = RadianceBank::WindowLength(frame.time_index, config_.context_window);
  window_.resize(std::size_t(length) * RadianceBank::kColumns);
  bank_.Window(frame.time_index, config_.context_window, window_.data(),
               config_.unseen_rows == "interpolate" ? UnseenRows::kInterpolate : UnseenRows::kZero);
  core_.BeginFrame(params_.data(), window_.data(), length, frame.log_exposure);
}

void DynamicToneMapper::Map(const float* log_hdr, std::size_t n, float* ldr) const {
  core_.Map(log_hdr, n, ldr);
}

void DynamicToneMapper::MapBackward(const float* log_hdr,
                                    std::size_t n,
                                    const float* dL_dldr,
                                    float* dL_dlog_hdr) {
  core_.MapBackward(log_hdr, n, dL_dldr, dL_dlog_hdr);
}

void DynamicToneMapper::EndFrameBackward() {
  HDR4D_CHECK(grads_.size() == core_.shape().NumParams());
  core_.EndFrameBackward(grads_.data());
}

void DynamicToneMapper::ObserveMeanLogHdr(int time_index, const float* mean_log_hdr) {
  CheckTimeIndex(time_index, "observed");
  bank_.Write(time_index, mean_log_hdr);
}

void DynamicToneMapper::Save(std::ostream& out) const {
  HashingWriter w(out);
  w.Bytes(kDtmMagic, sizeof(kDtmMagic));
  w.Value(kDtmVersion);
  w.ResetHash();
  const std::string json = config_.ToJson().dump();
  w.Value(static_cast<std::uint32_t>(json.size()));
  w.Bytes(json.data(), json.size());
  w.Value(static_cast<std::uint64_t>(params_.size()));
  w.Bytes(params_.data(), params_.size() * sizeof(float));
  w.Value(static_cast<std::uint32_t>(bank_.size()));
  w.Bytes(bank_.rows().data(), bank_.rows().size() * sizeof(float));
  w.Bytes(bank_.written_rows().data(), bank_.written_rows().size());
  w.Value(w.hash());
}

void DynamicToneMapper::Load(std::istream& in, const std::string& source) {
  HashingReader r(in, source, "tone mapper state");
  char magic[sizeof(kDtmMagic)];
  r.Bytes(magic, sizeof(magic), "the header");
  if (std::memcmp(magic, kDtmMagic, sizeof(kDtmMagic)) != 0) {
    Fail("{}: not a Dynamic Tone Mapper state (bad magic; expected \"HDR4DDTM\")", source);
  }
  const auto version = r.Value<std::uint32_t>("the version");
  if (version != 1 && version != kDtmVersion) {
    Fail("{}: tone mapper state version {} is not supported (this build reads versions 1 and {})",
         source, version, kDtmVersion);
  }
  r.ResetHash();
  const auto json_size = r.Value<std::uint32_t>("the configuration size");
  if (json_size > kMaxConfigBytes) {
    Fail("{}: tone mapper state claims a {}-byte configuration (corrupt)", source, json_size);
  }
  std::string json_text(json_size, '\0');
  r.Bytes(json_text.data(), json_size, "the configuration");
  const auto count = r.Value<std::uint64_t>("the parameter count");
  if (count != params_.size()) {
    Fail("{}: tone mapper state has {} parameters, this configuration needs {}", source, count,
         params_.size());
  }
  const std::vector<float> params = r.Floats(count, "the parameters");
  const auto rows = r.Value<std::uint32_t>("the radiance bank size");
  if (rows != static_cast<std::uint32_t>(bank_.size())) {
    Fail("{}: tone mapper state has {} radiance bank rows, this scene has {} timestamps", source,
         rows, bank_.size());
  }
  const std::vector<float> bank =
      r.Floats(std::uint64_t(rows) * RadianceBank::kColumns, "the radiance bank");
  std::vector<std::uint8_t> written(rows, 0);
  if (version >= 2) r.Bytes(written.data(), written.size(), "the radiance bank's written flags");
  r.VerifyChecksum();

  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: tone mapper state has an unreadable configuration: {}", source, e.what());
  }
  const ToneMapperConfig saved = ToneMapperConfig::FromJson(json, source);
  auto differs = [&](const char* key, const auto& a, const auto& b) {
    if (a != b) {
      Fail("{}: tone mapper state was saved with {} = {}, this run has {} = {}", source, key, a,
           key, b);
    }
  };
  differs("kind", saved.kind, config_.kind);
  differs("context_learner", saved.context_learner, config_.context_learner);
  differs("context_window", saved.context_window, config_.context_window);
  differs("context_size", saved.context_size, config_.context_size);
  differs("curve_hidden", saved.curve_hidden, config_.curve_hidden);
  differs("monotone_curves", saved.monotone_curves, config_.monotone_curves);
  differs("num_times", saved.num_times, config_.num_times);
  differs("unseen_rows", saved.unseen_rows, config_.unseen_rows);
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (!std::isfinite(params[i])) {
      Fail("{}: tone mapper state has a non-finite parameter (index {})", source, i);
    }
  }
  for (std::size_t i = 0; i < bank.size(); ++i) {
    if (!std::isfinite(bank[i])) {
      Fail("{}: tone mapper state has a non-finite radiance bank value (row {})", source,
           i / RadianceBank::kColumns);
    }
  }
  for (std::size_t i = 0; i < written.size(); ++i) {
    if (written[i] > 1) {
      Fail("{}: tone mapper state has a bad radiance bank written flag (row {})", source, i);
    }
  }
  // Version 1 saved no flags: a row is written where it is not all zero.
  if (version == 1) written = RadianceBank::WrittenWhereNonZero(bank);
  // Commit: nothing below can fail.
  std::copy(params.begin(), params.end(), params_.begin());
  bank_.SetRows(bank, written);
  core_.Invalidate();
}

}  // namespace hdr4d::method
