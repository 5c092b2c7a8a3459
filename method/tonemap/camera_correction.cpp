#include "method/tonemap/camera_correction.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d::method {

namespace {

constexpr double kCorrectionBeta1 = 0.9, kCorrectionBeta2 = 0.999, kCorrectionEps = 1e-8;

// One array of the record: `count` finite numbers.
std::vector<double> ReadCorrectionArray(const nlohmann::json& record, const char* key,
                                        std::size_t count, const std::string& source) {
  const auto it = record.find(key);
  if (it == record.end() || !it->is_array() || it->size() != count)
    Fail("{}: {}.{} must be an array of {} numbers", source, kCameraCorrectionKey, key, count);
  std::vector<double> values;
  for (const auto& v : *it) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      Fail("{}: {}.{} holds a value that is not a finite number", source, kCameraCorrectionKey,
           key);
    values.push_back(v.get<double>());
  }
  return values;
}

}  // namespace

CameraCorrectedToneMapper::CameraCorrectedToneMapper(std::unique_ptr<ToneMapper> inner,
                                                     int cameras, CameraCorrectionOptions options)
    : inner_(std::move(inner)), options_(options) {
  HDR4D_CHECK(inner_ && cameras >= 1);
  const std::size_t n = static_cast<std::size_t>(cameras) * 3;
  log_gain_.assign(n, 0.0f);
  grad_.assign(n, 0.0f);
  m_.assign(n, 0.0f);
  v_.assign(n, 0.0f);
  steps_.assign(cameras, 0);
  seen_.assign(cameras, 0);
}

void CameraCorrectedToneMapper::BeginFrame(const ToneFrame& frame) {
  row_ = frame.camera_index >= 0 && frame.camera_index < cameras() ? frame.camera_index : -1;
  for (int c = 0; c < 3; ++c) shift_[c] = row_ >= 0 ? log_gain_[row_ * 3 + c] : 0.0f;
  inner_->BeginFrame(frame);
}

const float* CameraCorrectedToneMapper::Shifted(const float* log_hdr, std::size_t n,
                                                std::vector<float>* scratch) const {
  if (row_ < 0) return log_hdr;  // the identity: the inner mapper's own input
  scratch->resize(n * 3);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) (*scratch)[i * 3 + c] = log_hdr[i * 3 + c] + shift_[c];
  return scratch->data();
}

// dL/dd_k = the sum over every value of dL/d(input), per channel; serial in double, so the same
// at any thread count.
void CameraCorrectedToneMapper::AddGrad(const float* dL_dx, std::size_t n) {
  if (row_ < 0) return;
  double sum[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) sum[c] += dL_dx[i * 3 + c];
  for (int c = 0; c < 3; ++c) grad_[row_ * 3 + c] += static_cast<float>(sum[c]);
  seen_[row_] = 1;
}

void CameraCorrectedToneMapper::Map(const float* log_hdr, std::size_t n, float* ldr) const {
  thread_local std::vector<float> scratch;  // Map is const and may run on several threads
  inner_->Map(Shifted(log_hdr, n, &scratch), n, ldr);
}

void CameraCorrectedToneMapper::MapBackward(const float* log_hdr, std::size_t n,
                                            const float* dL_dldr, float* dL_dlog_hdr) {
  float* dx = dL_dlog_hdr;
  if (!dx && row_ >= 0) {
    backward_scratch_.resize(n * 3);
    dx = backward_scratch_.data();
  }
  inner_->MapBackward(Shifted(log_hdr, n, &input_scratch_), n, dL_dldr, dx);
  if (dx) AddGrad(dx, n);
}

void CameraCorrectedToneMapper::MapImage(const float* log_hdr, int width, int height,
                                         float* ldr) const {
  thread_local std::vector<float> scratch;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  inner_->MapImage(Shifted(log_hdr, n, &scratch), width, height, ldr);
}

void CameraCorrectedToneMapper::MapImageBackward(const float* log_hdr, int width, int height,
                                                 const float* dL_dldr, float* dL_dlog_hdr) {
  const std::size_t n = static_cast<std::size_t>(width) * height;
  float* dx = dL_dlog_hdr;
  if (!dx && row_ >= 0) {
    backward_scratch_.resize(n * 3);
    dx = backward_scratch_.data();
  }
  inner_->MapImageBackward(Shifted(log_hdr, n, &input_scratch_), width, height, dL_dldr, dx);
  if (dx) AddGrad(dx, n);
}

void CameraCorrectedToneMapper::ZeroGrad() {
  std::fill(grad_.begin(), grad_.end(), 0.0f);
  std::fill(seen_.begin(), seen_.end(), std::uint8_t{0});
}

void CameraCorrectedToneMapper::ScaleGrad(float factor) {
  for (float& g : grad_) g *= factor;
}

double CameraCorrectedToneMapper::Regulariser() const {
  double sum = 0;
  for (int k = 0; k < cameras(); ++k) {
    if (!seen_[k]) continue;
    for (int c = 0; c < 3; ++c) sum += double(log_gain_[k * 3 + c]) * log_gain_[k * 3 + c];
  }
  return options_.weight * sum;
}

// Adam (as adam.h writes it, in double here: three values a camera) on the rows seen, with the
// regulariser's gradient 2 weight d added.
void CameraCorrectedToneMapper::Step() {
  for (int k = 0; k < cameras(); ++k) {
    if (!seen_[k]) continue;
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(grad_[k * 3 + c]))
        Fail("train: non-finite gradient in the camera correction of camera {}", k);
    }
    const std::int64_t step = ++steps_[k];
    const double bias1 = 1 - std::pow(kCorrectionBeta1, double(step));
    const double bias2 = 1 - std::pow(kCorrectionBeta2, double(step));
    for (int c = 0; c < 3; ++c) {
      const std::size_t i = static_cast<std::size_t>(k) * 3 + c;
      const double g = grad_[i] + 2 * options_.weight * log_gain_[i];
      const double m = kCorrectionBeta1 * m_[i] + (1 - kCorrectionBeta1) * g;
      const double v = kCorrectionBeta2 * v_[i] + (1 - kCorrectionBeta2) * g * g;
      m_[i] = static_cast<float>(m);
      v_[i] = static_cast<float>(v);
      log_gain_[i] -= static_cast<float>(options_.lr * (m / bias1) /
                                         (std::sqrt(v / bias2) + kCorrectionEps));
    }
  }
}

nlohmann::json CameraCorrectedToneMapper::ToJson() const {
  return {{"log_gain", log_gain_}, {"adam_m", m_}, {"adam_v", v_}, {"adam_steps", steps_}};
}

void CameraCorrectedToneMapper::FromJson(const nlohmann::json& trainer,
                                         const std::string& source) {
  const auto it = trainer.find(kCameraCorrectionKey);
  if (it == trainer.end() || !it->is_object())
    Fail("{}: the checkpoint has no {} (the run was started without --camera-correction?)",
         source, kCameraCorrectionKey);
  const std::size_t n = log_gain_.size();
  const std::vector<double> gain = ReadCorrectionArray(*it, "log_gain", n, source);
  const std::vector<double> m = ReadCorrectionArray(*it, "adam_m", n, source);
  const std::vector<double> v = ReadCorrectionArray(*it, "adam_v", n, source);
  const std::vector<double> steps = ReadCorrectionArray(*it, "adam_steps", n / 3, source);
  // Every value checked before any is taken: a refused record changes nothing.
  for (double x : v) {
    if (x < 0) Fail("{}: {}.adam_v holds a negative value", source, kCameraCorrectionKey);
  }
  for (double k : steps) {
    if (k < 0 || k != std::floor(k) || k > 1e15)
      Fail("{}: {}.adam_steps must hold counts >= 0", source, kCameraCorrectionKey);
  }
  for (std::size_t i = 0; i < n; ++i) {
    log_gain_[i] = static_cast<float>(gain[i]);
    m_[i] = static_cast<float>(m[i]);
    v_[i] = static_cast<float>(v[i]);
  }
  for (std::size_t k = 0; k < steps.size(); ++k) steps_[k] = static_cast<std::int64_t>(steps[k]);
}

}  // namespace hdr4d::method
