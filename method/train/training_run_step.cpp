// TrainingRun's step: one view (or batch) rendered, its loss, the backward pass, the optimiser's
// update, densification and the progress line.
#include "method/train/training_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/util/error.h"
#include "core/util/free_memory.h"
#include "core/util/parallel.h"
#include "method/optim/time_order.h"
#include "method/render/frame_render.h"
#include "method/train/batch_gradients.h"
#include "method/train/coarse_images.h"
#include "method/train/loss.h"
#include "method/train/tone_curve_watch.h"

namespace hdr4d::method::training_run {

double TrainingRun::TrainingSeconds() const {
  return seconds_before_ - eval_seconds_ +
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool TrainingRun::OutOfTime() const {
  return options_.max_seconds > 0 && TrainingSeconds() >= options_.max_seconds;
}

// One iteration: pick a view (a batch of them with --batch-size), render it, the loss, the
// backward with the fused optimiser step, the periodic held-out evaluation, densification,
// progress and the checkpoint.
void TrainingRun::Step() {
  const int it = ++loop_.iteration;
  head_current_ = false;
  best_val_restored_ = false;
  optimizer_->SetIteration(it);
  if (bands_) bands_->Begin(it, model_.size());
  SetColorDegrees(it);
  render_.track_max_weight = opt_.prune_contribution > 0 && it < opt_.densify_until;
  if (tone_mapper_) tone_mapper_->ZeroGrad();  // a batch adds every view's gradient to it
  if (background_) background_->ZeroGrad();
  if (correction_) correction_->ZeroGrad();
  const float* ldr_out = nullptr;  // the final LDR image of the last view, for the PSNR shown
  std::size_t pixels = 0;
  if (opt_.batch_size == 1) {
    const TrainView& view = train_views_[loop_.NextView(train_views_.size())];
    const double loss_value = ViewLoss(view, it, &ldr_out, &pixels);
    std::optional<double> psnr;
    BackwardAndUpdate(view, it, loss_value, [&] {
      if (ldr_out) psnr = TrainingPsnr(ldr_out, pixels);
    });
    ShowProgress(loss_value, psnr);
  } else {
    const double loss_value = BatchBackwardAndUpdate(it, &ldr_out, &pixels);
    ShowProgress(loss_value, ldr_out ? std::optional(TrainingPsnr(ldr_out, pixels)) : std::nullopt);
  }
  CheckpointIfDue(it);
  if (it % kToneCurveCheckEvery == 0) FlatToneCurveCheck(it);
}

// The view's buffers, its forward and loss; a non-finite loss stops training.
double TrainingRun::ViewLoss(const TrainView& view, int it, const float** ldr_out,
                             std::size_t* pixels) {
  coarse_ = CoarseFactor(it, opt_.coarse_to_fine, view.width(), view.height());
  camera_ = view.camera;
  if (coarse_ > 1) camera_.intrinsics = CoarseIntrinsics(view.camera.intrinsics, coarse_);
  *pixels = static_cast<std::size_t>(camera_.intrinsics.width) * camera_.intrinsics.height;
  image_.resize(*pixels * raster_channels_);
  dL_dimage_.resize(*pixels * raster_channels_);
  // The backward reads this view's forward image for the radiance shares (RenderOptions).
  render_.share_image = opt_.prune_radiance_share ? image_.data() : nullptr;
  view.ToFloat(&gt_);
  BoxReduceInPlace(&gt_, view.width(), view.height(), 3, coarse_);
  const double loss_value = ForwardAndLoss(view, ldr_out);
  if (!std::isfinite(loss_value)) {
    Fail("train: iteration {}: the loss is {} (view {}); stopped, {}", it, loss_value, view.name,
         WhatIsKept());
  }
  return loss_value;
}

// Renders `view` and returns the loss of every supervision term; *ldr_out is the final LDR
// image the loss made (null under HDR-only supervision).
double TrainingRun::ForwardAndLoss(const TrainView& view, const float** ldr_out) {
  geometry_split_ = false;
  const int width = camera_.intrinsics.width, height = camera_.intrinsics.height;
  if (!resolved_.hdr_colors) {
    RenderForward(model_, camera_, view.time, render_, &state_, image_.data());
    *ldr_out = image_.data();
    return PhotometricLoss(image_.data(), gt_.data(), width, height, 3,
                           static_cast<float>(opt_.lambda_dssim), dL_dimage_.data())
        .value;
  }
  stage_->SetFrame({view.time_index, view.image_index, static_cast<float>(std::log(view.exposure)),
                    view.camera_index},
                   /*observe_bank=*/true);
  RenderForward(model_, camera_, view.time, render_, &state_, image_.data());
  const float* mu = nullptr;
  if (!view.hdr_mu.empty()) {
    view.HdrMuToFloat(&hdr_mu_);
    // Reduced as mu values (the log-like target), not as radiance: a coarse step's target only.
    BoxReduceInPlace(&hdr_mu_, view.width(), view.height(), 3, coarse_);
    mu = hdr_mu_.data();
  }
  float* geometry = nullptr;
  if (!terms_.hdr_geometry) {
    dL_dgeometry_.resize(dL_dimage_.size());
    geometry = dL_dgeometry_.data();
  }
  const FrameLoss loss =
      HdrFrameLoss(image_.data(), raster_channels_, width, height, gt_.data(), mu,
                   tone_mapper_.get(), terms_, &scratch_, dL_dimage_.data(), geometry);
  geometry_split_ = loss.geometry_split;
  // The loss already made the final LDR image: the 2D branch for whole-image mappers, else the
  // clamped 3D branch (none under HDR-only supervision).
  if (resolved_.final_ldr_from_pixels && terms_.ldr_pixel) {
    *ldr_out = scratch_.pixel_ldr.data();
  } else if (terms_.ldr_gaussian) {
    *ldr_out = scratch_.ldr.data();
  }
  return loss.total;
}

// A 4D model's Gaussians in the order their time windows open (time_order.h), in the model, the
// optimiser's moments (once registered) and the statistics.
void TrainingRun::OrderByTime() {
  if (!model_.temporal || train_views_.empty()) return;
  const auto [first, last] =
      std::minmax_element(train_views_.begin(), train_views_.end(),
                          [](const TrainView& a, const TrainView& b) { return a.time < b.time; });
  ReorderGaussians(VisibleTimeOrder(model_, first->time, last->time), &model_,
                   optimizer_ ? &optimizer_->adam() : nullptr, &stats_);
}

// As in the reference, densification replaces every parameter tensor, so no optimiser step
// happens on that iteration; an opacity reset replaces only the opacity.
bool TrainingRun::DensifiesAt(int it) const {
  return it < opt_.densify_until && it > opt_.densify_from && it % opt_.densification_interval == 0;
}
bool TrainingRun::ResetsOpacityAt(int it) const {
  return it < opt_.densify_until && it % opt_.opacity_reset_interval == 0;
}

// The leading floats of a colour_rest row that the active colour degrees use: the coefficients
// k = n F + lm with n <= time degree and lm < (sh degree + 1)^2 (row index (k - 1) channels).
// A probe's band is rendered but not stepped (color_bands.h).
std::size_t TrainingRun::ActiveRestColumns() const {
  if (bands_) return bands_->step_columns();
  return RestColumns({render_.sh_degree, render_.time_degree}, model_.basis, model_.channels);
}

// The colour degrees iteration `it` renders with: the reference's schedule, or the bands on and
// the one probed (--color-bands-by-need).
void TrainingRun::SetColorDegrees(int it) {
  BandDegrees d = bands_ ? bands_->render_degrees()
                         : ScheduledDegrees(it, model_.basis, model_.temporal,
                                            opt_.sh_increase_interval);
  render_.sh_degree = d.sh;
  render_.time_degree = d.time;
}

// During a probe the backward's colour rows also go to it, before the optimiser steps them.
// Without a row callback (a batch's or a densifying step's stored gradients) EndBandProbe takes
// them from grads_.
GradientRowsDone TrainingRun::WithBandProbe(GradientRowsDone step_rows) {
  if (!bands_ || !bands_->probing() || !step_rows) return step_rows;
  return [this, step = std::move(step_rows)](std::int64_t b, std::int64_t e,
                                             const GradientRows& rows) {
    bands_->Add(b, e, rows);
    step(b, e, rows);
  };
}

// After the backward and before a densification moves the rows: the probe's stored rows, and
// its decision when it ends.
void TrainingRun::EndBandProbe(int it, bool rows_stored) {
  if (!bands_ || !bands_->probing()) return;
  if (rows_stored && grads_.color_dc.size() == model_.color_dc.size())
    bands_->Add(0, static_cast<std::int64_t>(model_.size()),
                GradientRows{grads_.color_dc.data(), grads_.color_rest.data()});
  if (const std::optional<BandDecision> d = bands_->End(it, DensifiesAt(it))) {
    spdlog::info("train: iteration {}: colour band SH {} time {}: signal {:.3g} (DC {:.3g}) -> {}",
                 it, d->band.sh, d->band.time, d->signal, d->dc_signal,
                 d->switched_on ? "on" : "stays frozen");
  }
}

// The backward with the model's optimiser step fused into it, then FinishUpdate.
// `beside` runs alongside the backward (RunAlongside), which must not write what it reads: the
// progress PSNR, a sequential sum over the image that would otherwise leave a thread idle.
void TrainingRun::BackwardAndUpdate(const TrainView& view, int it, double loss_value,
                                    const std::function<void()>& beside) {
  const GradientRowsDone step_rows = WithBandProbe(
      optimizer_->Begin(DensifiesAt(it), ResetsOpacityAt(it), model_.size(), ActiveRestColumns()));
  // The backward reads the loss's gradient image and the render state, not the final LDR image
  // or the target.
  RunAlongside(beside, [&] {
    RenderBackward(model_, camera_, view.time, render_, &state_, dL_dimage_.data(), &grads_,
                   step_rows, GeometryGradient());
  });
  EndBandProbe(it, /*rows_stored=*/!step_rows);
  if (tone_mapper_) tone_mapper_->EndFrameBackward();
  if (it < opt_.densify_until)
    AccumulateStats(state_.splat_grads.mean2d, state_.screen_radius, camera_.intrinsics.width,
                    camera_.intrinsics.height, &stats_, coarse_);
  if (render_.track_max_weight) AccumulateMaxWeight(state_.splat_grads.max_weight, &stats_);
  FinishUpdate(it, loss_value);
}

// --batch-size B > 1 (the reference's batch): B views, each rendered and back-propagated on its
// own with its gradient summed into grads_; the sum divided by B (the loss is the batch mean),
// one optimiser step over all rows, the statistics of the batch (BatchStats). Returns the mean
// loss.
double TrainingRun::BatchBackwardAndUpdate(int it, const float** ldr_out, std::size_t* pixels) {
  const int batch = opt_.batch_size;
  // Zeroed in place: the optimiser's groups point into grads_.
  for (std::vector<float>* field : GradientFields(&grads_)) std::fill(field->begin(), field->end(), 0.0f);
  view_grads_.ZerosLike(model_);
  batch_stats_.Begin(model_.size());
  double loss_sum = 0;
  for (int b = 0; b < batch; ++b) {
    const TrainView& view = train_views_[loop_.NextView(train_views_.size())];
    loss_sum += ViewLoss(view, it, ldr_out, pixels);
    RenderBackward(model_, camera_, view.time, render_, &state_, dL_dimage_.data(),
                   &view_grads_, {}, GeometryGradient());
    if (tone_mapper_) tone_mapper_->EndFrameBackward();
    AddGradients(view_grads_, &grads_);
    if (it < opt_.densify_until)
      batch_stats_.Add(state_.splat_grads.mean2d, state_.screen_radius,
                       camera_.intrinsics.width, camera_.intrinsics.height, coarse_);
    if (render_.track_max_weight) AccumulateMaxWeight(state_.splat_grads.max_weight, &stats_);
  }
  const float inverse = 1.0f / static_cast<float>(batch);
  ScaleGradients(inverse, &grads_);
  if (tone_mapper_)
    for (float& g : tone_mapper_->grads()) g *= inverse;
  if (background_)
    for (float& g : background_->grads()) g *= inverse;
  if (correction_) correction_->ScaleGrad(inverse);
  const GradientRowsDone step_rows = WithBandProbe(
      optimizer_->Begin(DensifiesAt(it), ResetsOpacityAt(it), model_.size(), ActiveRestColumns()));
  if (step_rows) {
    const std::size_t channels = static_cast<std::size_t>(model_.channels);
    const std::size_t stride = model_.rest_stride();
    ParallelForChunks(static_cast<std::int64_t>(model_.size()), 1024,
                      [&](std::int64_t b, std::int64_t e) {
                        step_rows(b, e,
                                  GradientRows{grads_.color_dc.data() + b * channels,
                                               grads_.color_rest.data() + b * stride});
                      });
  }
  EndBandProbe(it, /*rows_stored=*/!step_rows);
  if (it < opt_.densify_until) batch_stats_.AddTo(&stats_);
  const double loss_value = loss_sum / batch;
  FinishUpdate(it, loss_value);
  return loss_value;
}

// What a run stopped by a non-finite value keeps: its last checkpoint, or nothing (a new run's
// folder is then removed, run_folder.h), which --checkpoint-every would have changed.
std::string TrainingRun::WhatIsKept() const {
  std::error_code ec;
  if (fs::exists(checkpoint_path_, ec))
    return fmt::format("the last good checkpoint is {}", checkpoint_path_.string());
  return "and no checkpoint was written yet (--checkpoint-every N keeps one every N iterations)";
}

// After the backward: the finite check, the steps the backward did not take, the held-out
// evaluations due, then densification and the opacity reset on their schedule.
void TrainingRun::FinishUpdate(int it, double loss_value) {
  // A non-finite gradient stops training: the state in memory is partly stepped and dropped,
  // the last checkpoint kept.
  if (const std::string bad = optimizer_->FirstNonFinite(); !bad.empty()) {
    Fail("train: iteration {}: non-finite gradient in parameter group '{}'; stopped, {}", it, bad,
         WhatIsKept());
  }
  loop_.loss_curve.push_back(loss_value);
  // On a densifying iteration this steps only the tone mapper and the background, which
  // densification leaves alone, so it may come first (ModelOptimizer::Finish).
  optimizer_->Finish();
  if (correction_) correction_->Step();
  // The held-out views are scored before this iteration's densification and opacity reset, as
  // the reference's training_report is: right after them the new Gaussians have not settled
  // and every opacity is 0.01, so a reading there (every one on a multiple of the interval)
  // read several dB low on a sparse capture. A run the val split stops here ends on the model
  // it scored. (A run's last iteration still densifies where its schedule says so, which no
  // default schedule does, so that a run extended with --resume continues exactly.)
  EvaluateHeldOut(it);
  if (Stopped()) return;
  if (DensifiesAt(it)) {
    DensifyParams params = DensifyParamsAt(opt_, extent_, it);
    if (const std::optional<GrowthStop> g = GrowthStopped()) {
      const auto frozen = static_cast<std::size_t>(g->gaussians);
      params.max_gaussians = params.max_gaussians > 0 ? std::min(params.max_gaussians, frozen)
                                                      : frozen;
    }
    DensifyAndPrune(&model_, &grads_, &optimizer_->adam(), &stats_, params, &loop_.rng);
    OrderByTime();
    ReturnFreedMemory();  // its temporaries (core/util/free_memory.h)
  }
  if (ResetsOpacityAt(it)) ResetOpacity(&model_, &optimizer_->adam());
}

// The training-view PSNR of the final LDR image against the target, in one sequential sum (the
// curve of results.json is bit for bit the seed binary's).
double TrainingRun::TrainingPsnr(const float* ldr_out, std::size_t pixels) const {
  double squared = 0;
  for (std::size_t i = 0; i < pixels * 3; ++i) {
    const double d = std::clamp(ldr_out[i], 0.0f, 1.0f) - gt_[i];
    squared += d * d;
  }
  return -10.0 * std::log10(std::max(squared / (pixels * 3), 1e-20));
}

// The loss, the training-view PSNR (none under HDR-only supervision) and the Gaussian count on
// the progress line; the PSNR is also kept for results.json.
void TrainingRun::ShowProgress(double loss_value, std::optional<double> psnr) {
  std::string shown = fmt::format("loss {:.4f}", loss_value);
  if (psnr) {
    loop_.psnr_curve.push_back(*psnr);
    shown += fmt::format(" psnr {:.2f}", *psnr);
  }
  progress_->Advance(1, fmt::format("{} N {}", shown, model_.size()));
}

}  // namespace hdr4d::method::training_run
