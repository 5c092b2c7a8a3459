#include "method/train/hdr_head_fit.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <fmt/format.h>

#include "core/util/error.h"
#include "method/train/checkpoint.h"

namespace hdr4d::method {

HdrHead ReadHdrHead(const Checkpoint& c, std::size_t gaussians, const std::string& path) {
  HdrHead head;
  if (c.extra_floats.size() <= kHdrHeadSection) return head;
  head.offset = c.extra_floats[kHdrHeadSection];
  if (head.offset.size() != gaussians * 3) {
    Fail("{}: the HDR head has {} offsets for {} Gaussians (expected 3 per Gaussian)", path,
         head.offset.size(), gaussians);
  }
  for (float d : head.offset)
    if (!std::isfinite(d)) Fail("{}: the HDR head has a non-finite offset", path);
  const auto it = c.trainer.find(kHdrHeadScaleKey);
  if (it == c.trainer.end() || !it->is_number())
    Fail("{}: the HDR head has no {} in the trainer state", path, kHdrHeadScaleKey);
  head.log_scale = it->get<float>();
  if (!std::isfinite(head.log_scale) || std::abs(head.log_scale) > 80.0f)
    Fail("{}: {} is {}, not a finite log factor", path, kHdrHeadScaleKey, head.log_scale);
  const auto bg = c.trainer.find(kHdrHeadBackgroundKey);
  if (bg == c.trainer.end()) return head;  // a fixed background (or a head from before)
  if (c.trainer.find(kLearnedBackgroundKey) == c.trainer.end())
    Fail("{}: the HDR head has a background offset ({}) but the run has no learned background",
         path, kHdrHeadBackgroundKey);
  if (!bg->is_array() || bg->size() != 3)
    Fail("{}: {} must hold 3 numbers", path, kHdrHeadBackgroundKey);
  for (const auto& v : *bg) {
    if (!v.is_number() || !std::isfinite(v.get<double>()) || std::abs(v.get<double>()) > 80.0)
      Fail("{}: {} holds {}, not a finite log offset", path, kHdrHeadBackgroundKey, v.dump());
    head.background.push_back(v.get<float>());
  }
  return head;
}

HdrHead FitHdrHead(const HdrHeadFit& fit, Progress* progress) {
  HDR4D_CHECK(fit.model && fit.views && fit.render.background.size() >= 3);
  // HDR channels only: half the blend's per-pixel work of the run's 6, and no tone mapping of
  // the Gaussians; the HDR values and their gradients are the same per channel.
  HdrColorStage stage(fit.tone_mapper, /*map_gaussians=*/false);
  constexpr int kChannels = 3;
  RenderOptions render = fit.render;
  render.color_stage = &stage;
  render.background.resize(kChannels);  // the HDR channels' fixed values
  const GaussianModel& model = *fit.model;
  std::vector<std::size_t> order;
  for (std::size_t v = 0; v < fit.views->size(); ++v)
    if (!(*fit.views)[v].hdr_mu.empty()) order.push_back(v);
  if (order.empty()) Fail("train: --hdr-head: no training view has HDR ground truth");

  HdrHead head;
  const std::size_t values = model.size() * 3;
  head.offset.assign(values, 0.0f);
  std::vector<float> grad(values, 0.0f), m(values, 0.0f), v(values, 0.0f);
  stage.SetHdrOffset(head.offset.data(), grad.data());
  // The backdrop's offset: 3 values, seen by every view with background pixels.
  std::vector<float> bg_grad, bg_m, bg_v;
  if (fit.background) {
    HDR4D_CHECK(fit.render.background_source == fit.background);
    head.background.assign(3, 0.0f);
    bg_grad.assign(3, 0.0f);
    bg_m.assign(3, 0.0f);
    bg_v.assign(3, 0.0f);
    fit.background->SetHdrOffset(head.background.data(), bg_grad.data());
  }
  // The run's background must not keep pointers into this fit's arrays, even if a step throws.
  struct Detach {
    LearnedBackground* background;
    ~Detach() {
      if (background) background->SetHdrOffset(nullptr, nullptr);
    }
  } detach{fit.background};

  SupervisionTerms terms = fit.terms;  // the HDR term alone, on the render's shape
  terms.ldr_gaussian = false;
  terms.ldr_pixel = false;
  terms.hdr = true;
  terms.hdr_align = true;
  terms.hdr_geometry = true;

  std::mt19937_64 rng(fit.seed ^ 0x68647268656164ull);  // its own stream: the run's is untouched
  std::size_t next = order.size();
  FrameState state;
  HdrLossScratch scratch;
  std::vector<float> raster, dL_draster, hdr_gt;
  std::vector<double> log_scales;
  constexpr float kBeta1 = 0.9f, kBeta2 = 0.999f, kEps = 1e-15f;  // the reference's Adam
  for (int k = 1; k <= fit.iterations; ++k) {
    if (next == order.size()) {
      std::shuffle(order.begin(), order.end(), rng);
      next = 0;
    }
    const TrainView& view = (*fit.views)[order[next++]];
    const std::size_t pixels = static_cast<std::size_t>(view.width()) * view.height();
    raster.resize(pixels * kChannels);
    dL_draster.resize(pixels * kChannels);
    view.HdrMuToFloat(&hdr_gt);  // no LDR term runs: the LDR image is not needed
    // The radiance bank is not written: the tone mapper's state stays the trained one.
    stage.SetFrame(
        {view.time_index, view.image_index, static_cast<float>(std::log(view.exposure))},
        /*observe_bank=*/false);
    RenderForward(model, view.camera, view.time, render, &state, raster.data());
    const FrameLoss loss =
        HdrFrameLoss(raster.data(), kChannels, view.width(), view.height(),
                     /*ldr_gt=*/nullptr, hdr_gt.data(), fit.tone_mapper, terms, &scratch,
                     dL_draster.data(), nullptr);
    if (!std::isfinite(loss.total))
      Fail("train: --hdr-head: step {}: the HDR loss is {} (view {})", k, loss.total, view.name);
    if (2 * k > fit.iterations && loss.hdr_scale > 0)
      log_scales.push_back(std::log(loss.hdr_scale));
    std::fill(bg_grad.begin(), bg_grad.end(), 0.0f);  // the background adds to it
    // The model's own gradients are not needed: only the offsets' (written by the stage and the
    // background as the blend's backward reaches them).
    RenderBackward(model, view.camera, view.time, render, &state, dL_draster.data(), nullptr);
    // Adam on the offsets of the Gaussians this view shows (their gradient rows were written).
    const float c1 = 1.0f - std::pow(kBeta1, static_cast<float>(k));
    const float c2 = 1.0f - std::pow(kBeta2, static_cast<float>(k));
    const auto adam = [&](std::size_t q, const std::vector<float>& g, std::vector<float>& mq,
                          std::vector<float>& vq, std::vector<float>& x) {
      mq[q] = kBeta1 * mq[q] + (1.0f - kBeta1) * g[q];
      vq[q] = kBeta2 * vq[q] + (1.0f - kBeta2) * g[q] * g[q];
      x[q] -= kHdrHeadLearningRate * (mq[q] / c1) / (std::sqrt(vq[q] / c2) + kEps);
    };
    for (const std::uint32_t i : state.visible)
      for (std::size_t q = std::size_t(i) * 3; q < std::size_t(i) * 3 + 3; ++q)
        adam(q, grad, m, v, head.offset);
    for (std::size_t q = 0; q < head.background.size(); ++q)
      adam(q, bg_grad, bg_m, bg_v, head.background);
    if (progress) progress->Advance(1, fmt::format("HDR head loss {:.4f}", loss.hdr));
  }
  if (!log_scales.empty()) {
    auto mid = log_scales.begin() + static_cast<std::ptrdiff_t>(log_scales.size() / 2);
    std::nth_element(log_scales.begin(), mid, log_scales.end());
    head.log_scale = static_cast<float>(*mid);
  }
  return head;
}

}  // namespace hdr4d::method
