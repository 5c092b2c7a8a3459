// The optimiser of one training run: Adam over the model's eight parameter groups and the tone
// mapper's parameters, with the model's step fused into the backward. The renderer knows nothing
// of it, nor it of the renderer: the renderer calls the GradientRowsDone callback that Begin
// returns (method/gaussian/gradient_rows.h) with each block of Gaussians whose gradient rows are
// final, and the block is stepped there, while its gradients are still in cache
// (fused_adam_step.h). Per iteration the trainer calls
//   SetIteration -> Begin -> (backward) -> FirstNonFinite -> Finish -> [evaluate, densify]
// (docs/ARCHITECTURE.md, "One training step").
#pragma once

#include <atomic>
#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/gaussian/gradient_rows.h"
#include "method/optim/adam.h"
#include "method/optim/lr_schedule.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

inline constexpr const char* kGroupToneMapper = "tone_mapper";
inline constexpr const char* kGroupBackground = "background";

class ModelOptimizer {
 public:
  // `options` resolved for the run (schedules), `extent` the scene's (position learning rate).
  ModelOptimizer(const OptimizationOptions& options, double extent);

  // A new run: registers the model groups (learning rates of iteration 0) and the tone mapper's
  // parameters when it has any (`tone_mapper` may be null). The optimiser keeps pointers into
  // model, gradients and mapper.
  void AddGroups(GaussianModel& model, GaussianGradients& grads, ToneMapper* tone_mapper);
  // A resumed run, after Load: points the loaded groups at the buffers.
  void BindGroups(GaussianModel& model, GaussianGradients& grads, ToneMapper* tone_mapper);

  // A learned background (learned_background.h): its own group at a fixed rate, registered after
  // the others, stepped at every iteration like the tone mapper (densification leaves it alone).
  void AddBackgroundGroup(std::vector<float>& params, std::vector<float>& grads, float lr);
  // A resumed run's, after Load; throws hdr4d::Error naming `source` when the state has none.
  void BindBackgroundGroup(std::vector<float>& params, std::vector<float>& grads,
                           const std::string& source);

  // The model's learning rates at `iteration` (position decays with the run's schedule).
  void SetIteration(int iteration);

  // Begins one step over `num_gaussians` rows. `densify`: this iteration densifies, which
  // replaces every model tensor, so no model group is stepped (as in the reference) and the
  // callback only checks colour rows that have no gradient buffer (empty when they have one);
  // `reset_opacity`: the opacity is reset instead of stepped. Returns the callback for
  // RenderBackward; this object must outlive the backward. `rest_columns`: the leading floats
  // of each colour_rest row that can have had a gradient so far (the coefficients of the active
  // degrees, which only grow); the others are skipped, exactly (AdamRowStep::LimitColumns).
  GradientRowsDone Begin(bool densify,
                         bool reset_opacity,
                         std::size_t num_gaussians,
                         std::size_t rest_columns = SIZE_MAX);
  // After the backward: the first group whose gradient held a NaN or an infinity this step, or
  // "". Such a state is partly stepped and must be dropped.
  std::string FirstNonFinite() const;
  // Steps what the backward did not: the tone mapper always; the model groups outside the fused
  // step unless this iteration densifies or resets them. On a densifying iteration it steps only
  // the tone mapper and the background, so it may come before the densification (the trainer
  // scores its held-out views in between).
  void Finish();

  // The Adam state, for densification (which resizes its groups), the opacity reset and
  // checkpoints (streamed from it: CheckpointSection::Of).
  Adam& adam() { return adam_; }
  const Adam& adam() const { return adam_; }
  // Throws hdr4d::Error naming `source`; call BindGroups after it.
  void Load(std::istream& in, const std::string& source) { adam_.Load(in, source); }

 private:
  OptimizationOptions options_;
  double extent_;
  Adam adam_;
  bool tone_mapper_group_ = false;
  bool background_group_ = false;
  bool densify_ = false;
  bool reset_opacity_ = false;
  std::vector<std::string> fused_;       // stepped inside the backward
  std::vector<std::string> unfused_;     // every other registered group
  std::optional<AdamRowStep> row_step_;  // the callback of Begin points at it
  // A densifying step's colour rows held a NaN or an infinity (CheckColourRows).
  std::atomic<bool> dc_bad_ = false, rest_bad_ = false;

  GradientRowsDone CheckColourRows(std::size_t num_gaussians);
};

}  // namespace hdr4d::method
