// Adaptive density control of 4D Gaussians as 4DGS / HDR-4DGS do it (ARCHITECTURE §4,
// "Optimisation"): screen-space gradient statistics, clone / split / prune
// with the matching Adam surgery, and the periodic opacity reset. Also the optimiser's parameter
// groups over a GaussianModel (one group per model buffer, named as the reference names them).
//
// Order of the Gaussians after DensifyAndPrune (fixed, as the reference's cat / prune produce):
//   1. the surviving original Gaussians, in their original order (split parents are removed);
//   2. the surviving clones, in the order of their originals;
//   3. the surviving split children, copy-major as torch's repeat(N, 1) lays them out: the first
//      child of every split parent (in parent order), then the second child of every parent.
// (The trainer then sorts a 4D model by the opening of its time windows: time_order.h.)
// Randomness: each child draws its offset from `rng` in that same order (4 normals in 4D, 3 in
// 3D mode), for every child, pruned or not, so the draws do not depend on the prune test.
//
// Adam step: in the reference the surgery replaces every parameter tensor, so the optimiser step
// of a densification iteration finds no gradients and skips every group (their step counts do
// not advance); an opacity reset does the same to the "opacity" group. The trainer reproduces
// that by not calling Adam::Step (resp. StepGroup(kGroupOpacity)) in such an iteration.
#pragma once

#include <array>
#include <cstddef>
#include <random>
#include <string>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/optim/adam.h"
#include "method/optim/lr_schedule.h"

namespace hdr4d::method {

// ---- Parameter groups ----------------------------------------------------------------------
// The reference's optimiser group names. "scaling" holds all four log-scales (the reference has
// "scaling" and "scaling_t" with the same learning rate). In 3D mode the t, time-scale and
// rotation_r entries are still registered: they receive zero gradients, which Adam skips.
inline constexpr const char* kGroupXyz = "xyz";
inline constexpr const char* kGroupT = "t";
inline constexpr const char* kGroupScaling = "scaling";
inline constexpr const char* kGroupRotation = "rotation";
inline constexpr const char* kGroupRotationR = "rotation_r";
inline constexpr const char* kGroupOpacity = "opacity";
inline constexpr const char* kGroupFDc = "f_dc";
inline constexpr const char* kGroupFRest = "f_rest";
inline constexpr std::array<const char*, 8> kModelGroups = {
    kGroupXyz,       kGroupT,       kGroupScaling, kGroupRotation,
    kGroupRotationR, kGroupOpacity, kGroupFDc,     kGroupFRest};

// Floats per Gaussian of a model group: xyz 3, t 1, scaling 4, rotation 4, rotation_r 4,
// opacity 1, f_dc C, f_rest (K-1) C (0 when the basis has a single coefficient). The name must be
// one of kModelGroups (checked).
std::size_t GroupRowWidth(const GaussianModel& model, const std::string& group);
// The model's buffer of each group, in kModelGroups order.
std::array<std::vector<float>*, kModelGroups.size()> ModelGroupBuffers(GaussianModel& model);

// Learning rates of the model groups (rotation_r shares rotation's, as in the reference).
struct ModelLearningRates {
  float xyz = 0.0f;
  float t = 0.0f;
  float scaling = 0.0f;
  float rotation = 0.0f;
  float opacity = 0.0f;
  float f_dc = 0.0f;
  float f_rest = 0.0f;
};
// The rates at `step` (xyz decays; the others are constant) for a scene of the given extent.
ModelLearningRates LearningRatesAt(const OptimizationOptions& options, double extent, int step);

// True when `grads` has no colour buffers while the model has colour: the colour gradient rows go
// from the backward straight to the optimiser (fused_adam_step.h) and are never stored, as the
// trainer does at batch size 1 (~0.6 KB per Gaussian saved). AddModelGroups, BindModelGroups and
// DensifyAndPrune accept such a buffer (and keep it so); its colour groups have no bound gradient
// and are stepped only through AdamRowStep.
bool ColourRowsOnly(const GaussianModel& model, const GaussianGradients& grads);

// First registration of the eight groups (in kModelGroups order) with zero moments. `grads` must
// have the model's shape, or be ColourRowsOnly (checked); the optimiser keeps pointers into both.
void AddModelGroups(GaussianModel& model,
                    GaussianGradients& grads,
                    const ModelLearningRates& rates,
                    Adam* adam);
// Points every group at the model / gradient buffers again (after any reallocation); each
// group's size must already match (checked).
void BindModelGroups(GaussianModel& model, GaussianGradients& grads, Adam* adam);
// Sets every group's learning rate.
void SetModelLearningRates(const ModelLearningRates& rates, Adam* adam);
// Capacity for `rows` Gaussians in every model buffer, gradient buffer (those that exist), Adam
// moment and densification statistic, then BindModelGroups. Densification up to that count then
// rebuilds the buffers in place: growing past a buffer's capacity holds its old and new contents
// at once (with the moments' doubling, up to three times the largest group: 0.7 GB per copy of
// the colour group at 1.28M Gaussians). Capacity never written costs address space, not memory.
struct DensifyStats;
void ReserveModelRows(GaussianModel& model,
                      GaussianGradients& grads,
                      Adam* adam,
                      DensifyStats* stats,
                      std::size_t rows);

// ---- Statistics ----------------------------------------------------------------------------
// Per Gaussian, over the iterations since the last densification: the summed screen-space
// gradient norm (reference xyz_gradient_accum) and the number of views it was visible in
// (denom), and its largest screen radius in pixels (max_radii2D). Floats, so a checkpoint can
// store them as they are (counts stay exact up to 2^24).
struct DensifyStats {
  std::vector<float> grad_accum;
  std::vector<float> denom;
  std::vector<float> max_radii;
  // --prune-contribution only (else empty): the largest blending weight alpha T the Gaussian
  // had at any pixel of the views since the last densification (AccumulateMaxWeight).
  std::vector<float> max_weight;

  std::size_t size() const { return denom.size(); }
  // n Gaussians, all statistics zero; max_weight is kept (n zeros) only when it was tracked.
  void Reset(std::size_t n);
  // accum / denom, 0 where the Gaussian was never visible.
  std::vector<float> MeanGradient() const;
};

// One rendered view (batch size 1; BatchStats below for larger batches). mean2d_grad: N x 2,
// dL/d(projected mean) in pixel units; radius: N screen radii (0 = not visible). For radius > 0
// it adds |(gx W/2, gy H/2)| — the gradient with respect to the NDC mean the reference's
// rasteriser reports, on which its threshold 2e-4 is defined — and counts the view; max_radii
// keeps the largest radius. Sizes must agree with stats (checked).
// reduction f > 1 (--coarse-to-fine): the view was rendered at 1/f of the training images'
// size (floored where f does not divide it: train/coarse_images.h). Its norm is divided by f
// and its radii multiplied by f, so both are in the units of the full-size images the threshold
// and the screen-size prune were resolved for (the threshold goes as 1 / image size:
// OptimizationOptions::Resolved).
void AccumulateStats(const std::vector<float>& mean2d_grad,
                     const std::vector<int>& radius,
                     int width,
                     int height,
                     DensifyStats* stats,
                     int reduction = 1);

// max_weight of every Gaussian raised to the view's (SplatGradients::max_weight: the largest
// alpha T at any pixel of the view). Sizes must agree (checked).
void AccumulateMaxWeight(const std::vector<float>& view_max_weight, DensifyStats* stats);

// The statistics of one batch of views (the reference's batch_size > 1 path,
// add_densification_stats_grad): each view's loss is divided by the batch size B, the per-view
// NDC gradient norms of a Gaussian are summed and multiplied by B / (the number of views it
// was visible in), and its denominator grows by one per batch. Add takes the gradient of the
// view's own loss (not divided by B), so the value added is the mean norm over the views that
// saw it; with one view it is AccumulateStats exactly. max_radii: the largest radius of the
// batch.
class BatchStats {
 public:
  void Begin(std::size_t n);  // a new batch over n Gaussians
  void Add(const std::vector<float>& mean2d_grad,
           const std::vector<int>& radius,
           int width,
           int height,
           int reduction = 1);
  void AddTo(DensifyStats* stats) const;  // sizes must agree (checked)

 private:
  std::vector<float> norm_sum_, count_, max_radius_;
};

// ---- Clone / split / prune -----------------------------------------------------------------
struct DensifyParams {
  float grad_threshold = 2e-4f;  // on the mean NDC gradient norm
  float percent_dense = 0.01f;   // clone when max spatial scale <= this x extent, else split
  float scene_extent = 1.0f;
  float min_opacity = 0.005f;      // prune sigmoid(logit) below this
  float max_screen_size = 0.0f;    // px; 0 = off (the reference: 20 after the first opacity reset)
  bool prune_large_world = false;  // also prune max spatial scale > 0.1 extent (same condition)
  // The reference resets max_radii2D to zero whenever it appends Gaussians, i.e. before every
  // prune test of a densification step, so its screen-size test never fires. false (default)
  // reproduces that; true tests the accumulated radii instead (new Gaussians count as 0).
  bool keep_radii_for_prune = false;
  // Gaussian budget (the reference's densify_until_num_points, 0 = none): a densification step
  // never takes the count past it. Of the clone / split candidates only the ones with the
  // largest mean gradient are kept (each adds one Gaussian); at or over the budget none is.
  std::size_t max_gaussians = 0;
  // Pruning by contribution (--prune-contribution, issue 55; 0 = off): an original Gaussian that
  // was visible in some view since the last densification (denom > 0) but whose largest blending
  // weight there (stats.max_weight) stayed below this is pruned; clone sources and split parents
  // are not tested (their gradient asked for more of them). Needs stats.max_weight when > 0.
  float min_contribution = 0.0f;
  // --clone-opacity-correction: a kept clone and its surviving source both get opacity
  // 1 - sqrt(1 - alpha), so that together they blend as the source alone did (DensifyAndPrune).
  bool clone_opacity_correction = false;

  // "" when usable, else the problem: threshold >= 0, percent_dense in (0, 1], extent > 0,
  // min_opacity in [0, 1), max_screen_size >= 0, all finite.
  std::string Validate() const;
};

// The reference's settings for a densification at `iteration` (counted from 1): the options'
// threshold, percent_dense, prune opacity and Gaussian budget, and once iteration > opacity_reset_interval the
// 20 px screen size and the world-size prune.
DensifyParams DensifyParamsAt(const OptimizationOptions& options, double extent, int iteration);

struct DensifyResult {
  std::size_t cloned = 0;  // copies appended
  std::size_t split = 0;   // parents split (each replaced by 2 children)
  std::size_t pruned = 0;  // removed by the prune test, among originals, clones and children
  // New size = old size + cloned + split - pruned.
};

// The opacity logit of each of two coincident copies that together blend as one Gaussian of
// opacity sigmoid(logit): alpha' = 1 - sqrt(1 - alpha) (--clone-opacity-correction). Finite for
// every finite logit, evaluated in double.
float HalvedCloneOpacityLogit(float logit);

// One densification step: mean gradient = accum / denom (0 where denom is 0).
//  BUDGET with max_gaussians > 0, candidates (clone and split alike) beyond max_gaussians - size
//    are dropped, lowest mean gradient first (ties: the later index); pruning still runs.
//  CLONE grad >= threshold and max(exp(log_scales xyz)) <= percent_dense x extent: exact copy
//    (with clone_opacity_correction, after pruning, the copy and its surviving source both take
//    HalvedCloneOpacityLogit of its opacity).
//  SPLIT grad >= threshold and max spatial scale > percent_dense x extent: 2 children, each at
//    (xyz, t) + R4 (eps o s4) with eps ~ N(0, I4), s4 = exp(log_scales), R4 = Rotation4D(q_l, q_r)
//    (3D mode: xyz + R3 (eps o s3) with R3 = Rotation3D(q_l); t and the time scale unchanged),
//    log-scales minus log(1.6) (the reference's / (0.8 N)), everything else copied; the parent
//    goes. Clones are never split (the reference pads their gradient with 0).
//  PRUNE (after both, over all) sigmoid(logit) < min_opacity, or max_radii > max_screen_size (if
//    > 0 and keep_radii_for_prune), or (prune_large_world and max spatial scale > 0.1 extent);
//    with min_contribution > 0 also originals seen but never blended above it (above).
// Adam: survivors keep their moments, new Gaussians get zero moments, step counts are kept;
// every group is rebound to the model and to `grads`, which is resized to the new count and
// zeroed. `stats` is reset to zeros of the new size. params must be valid, stats the model's
// size and the groups registered by AddModelGroups (checked).
DensifyResult DensifyAndPrune(GaussianModel* model,
                              GaussianGradients* grads,
                              Adam* adam,
                              DensifyStats* stats,
                              const DensifyParams& params,
                              std::mt19937_64* rng);

// Opacity reset: opacity = min(opacity, max_opacity), done in logit space (a logit above
// logit(max_opacity) becomes exactly that, the others are left bit-identical rather than
// round-tripped through the sigmoid), and the "opacity" group's moments zeroed as the
// reference's replace_tensor_to_optimizer does. max_opacity in (0, 1) (checked).
void ResetOpacity(GaussianModel* model, Adam* adam, float max_opacity = 0.01f);

}  // namespace hdr4d::method
