#include "method/optim/model_optimizer.h"

#include <algorithm>

#include "core/util/error.h"
#include "method/optim/densify.h"
#include "method/optim/fused_adam_step.h"

namespace hdr4d::method {

ModelOptimizer::ModelOptimizer(const OptimizationOptions& options, double extent)
    : options_(options), extent_(extent), adam_(AdamOptions{.eps = options.adam_eps}) {
  // --visible-adam: the model's row steps skip the Gaussians a view did not see (adam.h,
  // "Visible rows"); the tone mapper and the background are whole-group steps, always dense.
  adam_.SetVisibleRows(options.visible_adam);
}

void ModelOptimizer::AddGroups(GaussianModel& model,
                               GaussianGradients& grads,
                               ToneMapper* tone_mapper) {
  AddModelGroups(model, grads, LearningRatesAt(options_, extent_, 0), &adam_);
  tone_mapper_group_ = tone_mapper && !tone_mapper->params().empty();
  if (!tone_mapper_group_) return;
  adam_.AddGroup({.name = kGroupToneMapper,
                  .params = tone_mapper->params().data(),
                  .grads = tone_mapper->grads().data(),
                  .size = tone_mapper->params().size(),
                  .lr = tone_mapper->learning_rate()});
}

void ModelOptimizer::BindGroups(GaussianModel& model,
                                GaussianGradients& grads,
                                ToneMapper* tone_mapper) {
  BindModelGroups(model, grads, &adam_);
  tone_mapper_group_ = tone_mapper && !tone_mapper->params().empty();
  if (!tone_mapper_group_) return;
  adam_.SetBuffers(kGroupToneMapper, tone_mapper->params().data(), tone_mapper->grads().data(),
                   tone_mapper->params().size());
}

void ModelOptimizer::AddBackgroundGroup(std::vector<float>& params, std::vector<float>& grads,
                                        float lr) {
  adam_.AddGroup({.name = kGroupBackground,
                  .params = params.data(),
                  .grads = grads.data(),
                  .size = params.size(),
                  .lr = lr});
  background_group_ = true;
}

void ModelOptimizer::BindBackgroundGroup(std::vector<float>& params, std::vector<float>& grads,
                                         const std::string& source) {
  const std::vector<std::string> names = adam_.GroupNames();
  if (std::find(names.begin(), names.end(), kGroupBackground) == names.end())
    Fail("{}: the checkpoint has no learned background (the run was started with "
         "--no-learn-background, or before the option existed: resume it with "
         "--no-learn-background)", source);
  adam_.SetBuffers(kGroupBackground, params.data(), grads.data(), params.size());
  background_group_ = true;
}

void ModelOptimizer::SetIteration(int iteration) {
  SetModelLearningRates(LearningRatesAt(options_, extent_, iteration), &adam_);
}

GradientRowsDone ModelOptimizer::Begin(bool densify,
                                       bool reset_opacity,
                                       std::size_t num_gaussians,
                                       std::size_t rest_columns) {
  densify_ = densify;
  reset_opacity_ = reset_opacity;
  dc_bad_ = rest_bad_ = false;
  fused_.clear();
  if (!densify) {
    for (const char* group : kModelGroups) {
      if (!(reset_opacity && std::string(group) == kGroupOpacity)) fused_.emplace_back(group);
    }
  }
  unfused_.clear();
  for (const std::string& group : adam_.GroupNames()) {
    if (std::find(fused_.begin(), fused_.end(), group) == fused_.end()) unfused_.push_back(group);
  }
  row_step_.emplace(adam_.BeginRowStep(fused_, num_gaussians));
  row_step_->LimitColumns(kGroupFRest, rest_columns);
  if (densify) return CheckColourRows(num_gaussians);
  return StepModelRows(fused_, &*row_step_);
}

// A densifying step moves no model group, but its colour rows are still checked for NaN and
// infinity. Where they have no gradient buffer (ColourRowsOnly) this callback is the only place
// they exist; where they have one, the backward writes them there and FirstNonFinite checks it.
GradientRowsDone ModelOptimizer::CheckColourRows(std::size_t num_gaussians) {
  const auto stored = [&](const char* name) {
    const AdamGroup& g = adam_.group(name);
    return g.size == 0 || g.grads != nullptr;
  };
  if (num_gaussians == 0 || (stored(kGroupFDc) && stored(kGroupFRest))) return {};
  const std::size_t dc_width = adam_.group(kGroupFDc).size / num_gaussians;
  const std::size_t rest_width = adam_.group(kGroupFRest).size / num_gaussians;
  return [this, dc_width, rest_width](std::int64_t b, std::int64_t e, const GradientRows& rows) {
    const auto count = static_cast<std::size_t>(e - b);
    if (!AllFinite(rows.color_dc, count * dc_width)) dc_bad_ = true;
    if (!AllFinite(rows.color_rest, count * rest_width)) rest_bad_ = true;
  };
}

std::string ModelOptimizer::FirstNonFinite() const {
  std::string bad = row_step_ ? row_step_->FirstNonFinite() : "";
  if (bad.empty()) bad = adam_.FirstNonFiniteGradient(unfused_);
  // The colour groups come after the other model groups and before the tone mapper and the
  // background.
  if (bad.empty() || bad == kGroupToneMapper || bad == kGroupBackground) {
    if (dc_bad_) return kGroupFDc;
    if (rest_bad_) return kGroupFRest;
  }
  return bad;
}

void ModelOptimizer::Finish() {
  row_step_.reset();
  if (densify_) {
    // Densification replaced the model tensors (they have no gradient now), but the reference's
    // step after it still moves the tone mapper, which densification leaves alone.
    if (tone_mapper_group_) adam_.StepGroup(kGroupToneMapper);
    if (background_group_) adam_.StepGroup(kGroupBackground);
    return;
  }
  for (const std::string& group : unfused_) {
    if (!(reset_opacity_ && group == kGroupOpacity)) adam_.StepGroup(group);
  }
}

}  // namespace hdr4d::method
