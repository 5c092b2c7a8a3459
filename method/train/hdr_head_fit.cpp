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
  // No section, or an empty one (a run that stores sections after it without a head).
  if (c.extra_floats.size() <= kHdrHeadSection || c.extra_floats[kHdrHeadSection].empty())
    return head;
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

namespace {

constexpr float kBeta1 = 0.9f, kBeta2 = 0.999f, kEps = 1e-15f;  // the reference's Adam

// Adam on one array of head values: its gradient (written by the blend's backward) and moments.
struct HeadAdam {
  std::vector<float> grad, m, v;
  explicit HeadAdam(std::size_t n = 0) : grad(n, 0.0f), m(n, 0.0f), v(n, 0.0f) {}
  // Steps value q of x; c1, c2: the step's bias corrections.
  void Step(std::size_t q, float c1, float c2, std::vector<float>& x) {
    m[q] = kBeta1 * m[q] + (1.0f - kBeta1) * grad[q];
    v[q] = kBeta2 * v[q] + (1.0f - kBeta2) * grad[q] * grad[q];
    x[q] -= kHdrHeadLearningRate * (m[q] / c1) / (std::sqrt(v[q] / c2) + kEps);
  }
};

// The training views with HDR targets, by index.
std::vector<std::size_t> ViewsWithHdr(const std::vector<TrainView>& views) {
  std::vector<std::size_t> order;
  for (std::size_t v = 0; v < views.size(); ++v)
    if (!views[v].hdr_mu.empty()) order.push_back(v);
  if (order.empty()) Fail("train: --hdr-head: no training view has HDR ground truth");
  return order;
}

// The run's terms with the HDR term alone, on the render's shape (scale-aligned).
SupervisionTerms HeadTerms(const SupervisionTerms& run) {
  SupervisionTerms terms = run;
  terms.ldr_gaussian = false;
  terms.ldr_pixel = false;
  terms.hdr = true;
  terms.hdr_align = true;
  terms.hdr_geometry = true;
  return terms;
}

// What one step of the fit renders into and keeps between its forward and backward.
struct HeadStepBuffers {
  FrameState state;
  HdrLossScratch scratch;
  std::vector<float> raster, dL_draster, hdr_gt;
};

// The forward of one view (HDR channels alone) and its HDR loss; dL/draster in `b`.
FrameLoss HeadViewLoss(const HdrHeadFit& fit,
                       const RenderOptions& render,
                       HdrColorStage& stage,
                       const SupervisionTerms& terms,
                       const TrainView& view,
                       HeadStepBuffers* b) {
  constexpr int kChannels = 3;
  const std::size_t pixels = static_cast<std::size_t>(view.width()) * view.height();
  b->raster.resize(pixels * kChannels);
  b->dL_draster.resize(pixels * kChannels);
  view.HdrMuToFloat(&b->hdr_gt);  // no LDR term runs: the LDR image is not needed
  // The radiance bank is not written: the tone mapper's state stays the trained one.
  stage.SetFrame({view.time_index, view.image_index, static_cast<float>(std::log(view.exposure)),
                  view.camera_index},
                 /*observe_bank=*/false);
  RenderForward(*fit.model, view.camera, view.time, render, &b->state, b->raster.data());
  return HdrFrameLoss(b->raster.data(), kChannels, view.width(), view.height(),
                      /*ldr_gt=*/nullptr, b->hdr_gt.data(), fit.tone_mapper, terms, &b->scratch,
                      b->dL_draster.data(), nullptr);
}

double Median(std::vector<double> values) {
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

HdrHead FitHdrHead(const HdrHeadFit& fit, Progress* progress) {
  HDR4D_CHECK(fit.model && fit.views && fit.render.background.size() >= 3);
  // HDR channels only: half the blend's per-pixel work of the run's 6, and no tone mapping of
  // the Gaussians; the HDR values and their gradients are the same per channel.
  HdrColorStage stage(fit.tone_mapper, /*map_gaussians=*/false);
  RenderOptions render = fit.render;
  render.color_stage = &stage;
  render.background.resize(3);  // the HDR channels' fixed values
  std::vector<std::size_t> order = ViewsWithHdr(*fit.views);

  HdrHead head;
  head.offset.assign(fit.model->size() * 3, 0.0f);
  HeadAdam offsets(head.offset.size());
  stage.SetHdrOffset(head.offset.data(), offsets.grad.data());
  // The backdrop's offset: 3 values, seen by every view with background pixels.
  HeadAdam backdrop;
  if (fit.background) {
    HDR4D_CHECK(fit.render.background_source == fit.background);
    head.background.assign(3, 0.0f);
    backdrop = HeadAdam(3);
    fit.background->SetHdrOffset(head.background.data(), backdrop.grad.data());
  }
  // The run's background must not keep pointers into this fit's arrays, even if a step throws.
  struct Detach {
    LearnedBackground* background;
    ~Detach() {
      if (background) background->SetHdrOffset(nullptr, nullptr);
    }
  } detach{fit.background};

  const SupervisionTerms terms = HeadTerms(fit.terms);
  std::mt19937_64 rng(fit.seed ^ 0x68647268656164ull);  // its own stream: the run's is untouched
  std::size_t next = order.size();
  HeadStepBuffers buffers;
  std::vector<double> log_scales;
  for (int k = 1; k <= fit.iterations; ++k) {
    if (next == order.size()) {
      std::shuffle(order.begin(), order.end(), rng);
      next = 0;
    }
    const TrainView& view = (*fit.views)[order[next++]];
    const FrameLoss loss = HeadViewLoss(fit, render, stage, terms, view, &buffers);
    if (!std::isfinite(loss.total))
      Fail("train: --hdr-head: step {}: the HDR loss is {} (view {})", k, loss.total, view.name);
    if (2 * k > fit.iterations && loss.hdr_scale > 0)
      log_scales.push_back(std::log(loss.hdr_scale));
    std::fill(backdrop.grad.begin(), backdrop.grad.end(), 0.0f);  // the background adds to it
    // The model's own gradients are not needed: only the offsets' (written by the stage and the
    // background as the blend's backward reaches them).
    RenderBackward(*fit.model, view.camera, view.time, render, &buffers.state,
                   buffers.dL_draster.data(), nullptr);
    // Adam on the offsets of the Gaussians this view shows (their gradient rows were written).
    const float c1 = 1.0f - std::pow(kBeta1, static_cast<float>(k));
    const float c2 = 1.0f - std::pow(kBeta2, static_cast<float>(k));
    for (const std::uint32_t i : buffers.state.visible)
      for (std::size_t q = std::size_t(i) * 3; q < std::size_t(i) * 3 + 3; ++q)
        offsets.Step(q, c1, c2, head.offset);
    for (std::size_t q = 0; q < head.background.size(); ++q)
      backdrop.Step(q, c1, c2, head.background);
    if (progress) progress->Advance(1, fmt::format("HDR head loss {:.4f}", loss.hdr));
  }
  if (!log_scales.empty()) head.log_scale = static_cast<float>(Median(std::move(log_scales)));
  return head;
}

}  // namespace hdr4d::method
