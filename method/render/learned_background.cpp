#include "method/render/learned_background.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"
#include "method/render/hdr_color_stage.h"

namespace hdr4d::method {

int LearnedBackgroundChannels(const GaussianModel& model) {
  return model.color_mode == ColorMode::kLogHdr ? 3 : model.channels;
}

std::vector<float> ReadLearnedBackground(const nlohmann::json& trainer, int channels,
                                         const std::string& source) {
  const auto it = trainer.find(kLearnedBackgroundKey);
  if (it == trainer.end() || !it->is_array() || it->size() != std::size_t(channels))
    Fail("{}: the checkpoint has no learned background of {} values (the run was started "
         "with --no-learn-background, or before the option existed?)", source, channels);
  std::vector<float> values;
  for (const auto& v : *it) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      Fail("{}: {} holds a value that is not a finite number", source, kLearnedBackgroundKey);
    values.push_back(v.get<float>());
  }
  return values;
}

LearnedBackground::LearnedBackground(std::vector<float> values, bool log_hdr,
                                     ToneMapper* tone_mapper)
    : values_(std::move(values)), grads_(values_.size(), 0.0f), log_hdr_(log_hdr),
      tm_(tone_mapper) {
  HDR4D_CHECK(!log_hdr_ || values_.size() == 3);
}

void LearnedBackground::ZeroGrad() { std::fill(grads_.begin(), grads_.end(), 0.0f); }

void LearnedBackground::Forward(int channels, std::vector<float>* background) {
  background->assign(channels, 0.0f);
  if (!log_hdr_) {
    HDR4D_CHECK(channels == static_cast<int>(values_.size()));
    std::copy(values_.begin(), values_.end(), background->begin());
    return;
  }
  if (ldr_only_) {
    HDR4D_CHECK(channels == 3 && tm_ && tm_->pointwise());
    tm_->Map(values_.data(), 1, background->data());
    return;
  }
  HDR4D_CHECK(channels == 3 || (channels == 6 && tm_ && tm_->pointwise()));
  for (int c = 0; c < 3; ++c)
    (*background)[c] = GuardedExp(values_[c] + (offset_ ? offset_[c] : 0.0f));
  if (channels == 6) tm_->Map(values_.data(), 1, background->data() + 3);
}

void LearnedBackground::Backward(int channels, const float* dL_dbackground) {
  HDR4D_CHECK(!ldr_only_);
  if (!log_hdr_) {
    for (int c = 0; c < channels; ++c) grads_[c] += dL_dbackground[c];
    return;
  }
  for (int c = 0; c < 3; ++c) {
    const float g =
        GuardedExpBackward(values_[c] + (offset_ ? offset_[c] : 0.0f), dL_dbackground[c]);
    grads_[c] += g;
    if (offset_grad_) offset_grad_[c] += g;
  }
  if (channels != 6) return;
  // The slope of the mapper at b by central differences of Map, so that the backdrop moves b
  // and gives the tone curve no share of its gradient (header). Channels map independently.
  constexpr float kStep = 1e-3f;  // in log radiance
  float up[3], down[3], high[3], low[3];
  for (int c = 0; c < 3; ++c) {
    up[c] = values_[c] + kStep;
    down[c] = values_[c] - kStep;
  }
  tm_->Map(up, 1, high);
  tm_->Map(down, 1, low);
  for (int c = 0; c < 3; ++c)
    grads_[c] += (high[c] - low[c]) / (2 * kStep) * dL_dbackground[3 + c];
}

}  // namespace hdr4d::method
