#include "method/optim/densify.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/sigmoid.h"
#include "method/gaussian/rotation4d.h"

namespace hdr4d::method {

namespace {

constexpr int kSplitChildren = 2;  // the reference's N
// log(0.8 N): children's scales are the parent's divided by 1.6.
const float kLogSplitShrink = static_cast<float>(std::log(0.8 * kSplitChildren));
// Screen-size prune threshold in pixels after the first opacity reset (reference train.py).
constexpr float kMaxScreenSize = 20.0f;
// World-size prune: max spatial scale above this fraction of the extent.
constexpr double kLargeWorldFraction = 0.1;

// One model group: its name, the model and gradient buffers and the floats per Gaussian.
struct GroupBuffers {
  const char* name = nullptr;
  std::vector<float>* params = nullptr;
  std::vector<float>* grads = nullptr;
  std::size_t width = 0;
};

// In kModelGroups order.
std::array<GroupBuffers, kModelGroups.size()> Groups(GaussianModel& m, GaussianGradients& g) {
  const auto params = ModelGroupBuffers(m);
  const auto grads = ModelGroupBuffers(g);  // the same type: one gradient per parameter
  std::array<GroupBuffers, kModelGroups.size()> out;
  for (std::size_t k = 0; k < kModelGroups.size(); ++k) {
    out[k] = {kModelGroups[k], params[k], grads[k], GroupRowWidth(m, kModelGroups[k])};
  }
  return out;
}

// True when `grads` is a gradient buffer for `model`: the same shape, or the same without the
// colour buffers (ColourRowsOnly).
bool FitsModel(const GaussianModel& model, const GaussianGradients& grads) {
  const GaussianModel& a = model;
  const GaussianGradients& b = grads;
  return a.channels == b.channels && a.basis.max_sh_degree == b.basis.max_sh_degree &&
         a.basis.max_time_degree == b.basis.max_time_degree && a.xyz.size() == b.xyz.size() &&
         a.t.size() == b.t.size() && a.log_scales.size() == b.log_scales.size() &&
         a.rot_left.size() == b.rot_left.size() && a.rot_right.size() == b.rot_right.size() &&
         a.opacity_logit.size() == b.opacity_logit.size() &&
         ((a.color_dc.size() == b.color_dc.size() && a.color_rest.size() == b.color_rest.size()) ||
          ColourRowsOnly(model, grads));
}

// A group's gradient pointer: null for a colour group whose rows are never stored.
const float* GradientData(const std::vector<float>& grads, const std::vector<float>& params) {
  return grads.empty() && !params.empty() ? nullptr : grads.data();
}

// Standard normals by the Box-Muller transform from 53-bit uniforms, so the draws are the same
// with every standard library (std::normal_distribution's algorithm is unspecified).
class NormalSampler {
 public:
  explicit NormalSampler(std::mt19937_64* rng) : rng_(rng) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    constexpr double kScale = 1.0 / 9007199254740992.0;                     // 2^-53
    const double u1 = static_cast<double>(((*rng_)() >> 11) + 1) * kScale;  // (0, 1]
    const double u2 = static_cast<double>((*rng_)() >> 11) * kScale;        // [0, 1)
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    spare_ = r * std::sin(angle);
    has_spare_ = true;
    return r * std::cos(angle);
  }

 private:
  std::mt19937_64* rng_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

float MaxSpatialScale(const float* log_scales) {
  return std::exp(std::max({log_scales[0], log_scales[1], log_scales[2]}));
}

// Copies rows `rows` of `src` (width floats each) into a new buffer, in that order.
std::vector<float> GatherRows(const std::vector<float>& src,
                              const std::vector<std::uint32_t>& rows,
                              std::size_t width) {
  std::vector<float> out(rows.size() * width);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    std::copy_n(src.begin() + static_cast<std::size_t>(rows[k]) * width, width,
                out.begin() + k * width);
  }
  return out;
}

// *buf becomes its rows `kept` (increasing) followed by its rows `appended` (any order). In place
// when the result fits the capacity (no allocation, no page faults: a model of 10^5 - 10^6
// Gaussians is hundreds of MB), else through one buffer of exactly the new size.
void RebuildRows(std::vector<float>* buf,
                 const std::vector<std::uint32_t>& kept,
                 const std::vector<std::uint32_t>& appended,
                 std::size_t width) {
  if (width == 0) return;
  const std::size_t total = (kept.size() + appended.size()) * width;
  if (total > buf->capacity()) {
    std::vector<float> out;
    out.reserve(total);
    for (const auto* rows : {&kept, &appended}) {
      for (const std::size_t r : *rows) {
        out.insert(out.end(), buf->begin() + r * width, buf->begin() + (r + 1) * width);
      }
    }
    buf->swap(out);
    return;
  }
  const std::vector<float> extra = GatherRows(*buf, appended, width);
  // kept[k] >= k, so moving rows forward in order never overwrites a row still to be read.
  for (std::size_t k = 0; k < kept.size(); ++k) {
    if (kept[k] != k) {
      std::copy_n(buf->begin() + static_cast<std::size_t>(kept[k]) * width, width,
                  buf->begin() + k * width);
    }
  }
  buf->resize(kept.size() * width);
  buf->insert(buf->end(), extra.begin(), extra.end());
}

}  // namespace

// ---- Parameter groups ----------------------------------------------------------------------

std::size_t GroupRowWidth(const GaussianModel& model, const std::string& group) {
  if (group == kGroupXyz) return 3;
  if (group == kGroupT || group == kGroupOpacity) return 1;
  if (group == kGroupScaling || group == kGroupRotation || group == kGroupRotationR) return 4;
  if (group == kGroupFDc) return static_cast<std::size_t>(model.channels);
  HDR4D_CHECK(group == kGroupFRest);
  return model.rest_stride();
}

std::array<std::vector<float>*, kModelGroups.size()> ModelGroupBuffers(GaussianModel& m) {
  return {&m.xyz,           &m.t,        &m.log_scales, &m.rot_left, &m.rot_right,
          &m.opacity_logit, &m.color_dc, &m.color_rest};
}

ModelLearningRates LearningRatesAt(const OptimizationOptions& options, double extent, int step) {
  ModelLearningRates r;
  r.xyz = static_cast<float>(options.PositionLr(extent)(step));
  r.t = static_cast<float>(options.TLr(extent)(step));
  r.scaling = static_cast<float>(options.scaling_lr);
  r.rotation = static_cast<float>(options.rotation_lr);
  r.opacity = static_cast<float>(options.opacity_lr);
  r.f_dc = static_cast<float>(options.f_dc_lr);
  r.f_rest = static_cast<float>(options.f_rest_lr);
  return r;
}

namespace {
float RateOf(const ModelLearningRates& r, const std::string& name) {
  if (name == kGroupXyz) return r.xyz;
  if (name == kGroupT) return r.t;
  if (name == kGroupScaling) return r.scaling;
  if (name == kGroupRotation || name == kGroupRotationR) return r.rotation;
  if (name == kGroupOpacity) return r.opacity;
  if (name == kGroupFDc) return r.f_dc;
  return r.f_rest;
}
}  // namespace

void AddModelGroups(GaussianModel& model,
                    GaussianGradients& grads,
                    const ModelLearningRates& rates,
                    Adam* adam) {
  HDR4D_CHECK(adam != nullptr);
  HDR4D_CHECK(model.Validate().empty());
  HDR4D_CHECK(FitsModel(model, grads));
  for (const GroupBuffers& g : Groups(model, grads)) {
    adam->AddGroup({g.name, g.params->data(), GradientData(*g.grads, *g.params), g.params->size(),
                    RateOf(rates, g.name)});
  }
}

bool ColourRowsOnly(const GaussianModel& model, const GaussianGradients& grads) {
  return grads.color_dc.empty() && grads.color_rest.empty() &&
         (!model.color_dc.empty() || !model.color_rest.empty());
}

void BindModelGroups(GaussianModel& model, GaussianGradients& grads, Adam* adam) {
  HDR4D_CHECK(adam != nullptr);
  HDR4D_CHECK(FitsModel(model, grads));
  for (const GroupBuffers& g : Groups(model, grads)) {
    adam->SetBuffers(g.name, g.params->data(), GradientData(*g.grads, *g.params),
                     g.params->size());
  }
}

void SetModelLearningRates(const ModelLearningRates& rates, Adam* adam) {
  HDR4D_CHECK(adam != nullptr);
  for (const char* name : kModelGroups) adam->SetLearningRate(name, RateOf(rates, name));
}

void ReserveModelRows(GaussianModel& model,
                      GaussianGradients& grads,
                      Adam* adam,
                      DensifyStats* stats,
                      std::size_t rows) {
  HDR4D_CHECK(adam != nullptr && stats != nullptr);
  for (const GroupBuffers& g : Groups(model, grads)) {
    if (g.width == 0) continue;
    g.params->reserve(rows * g.width);
    if (!g.grads->empty()) g.grads->reserve(rows * g.width);
    adam->ReserveGroup(g.name, rows * g.width);
  }
  for (auto* v : {&stats->grad_accum, &stats->denom, &stats->max_radii}) v->reserve(rows);
  if (!stats->max_weight.empty()) stats->max_weight.reserve(rows);
  BindModelGroups(model, grads, adam);
}

// ---- Statistics ----------------------------------------------------------------------------

void DensifyStats::Reset(std::size_t n) {
  grad_accum.assign(n, 0.0f);
  denom.assign(n, 0.0f);
  max_radii.assign(n, 0.0f);
  if (!max_weight.empty()) max_weight.assign(n, 0.0f);
}

std::vector<float> DensifyStats::MeanGradient() const {
  HDR4D_CHECK(grad_accum.size() == denom.size());
  std::vector<float> mean(denom.size(), 0.0f);
  for (std::size_t i = 0; i < denom.size(); ++i) {
    if (denom[i] > 0.0f) mean[i] = grad_accum[i] / denom[i];
  }
  return mean;
}

// Gaussians per chunk of the per-view statistics (a chunk costs a wake-up).
constexpr std::int64_t kStatsGrain = 8192;

void AccumulateStats(const std::vector<float>& mean2d_grad,
                     const std::vector<int>& radius,
                     int width,
                     int height,
                     DensifyStats* stats,
                     int reduction) {
  HDR4D_CHECK(stats != nullptr && width > 0 && height > 0 && reduction >= 1);
  const std::size_t n = radius.size();
  HDR4D_CHECK(mean2d_grad.size() == 2 * n && stats->grad_accum.size() == n &&
              stats->denom.size() == n && stats->max_radii.size() == n);
  // d(pixel)/d(NDC) = size / 2, so the NDC gradient is the pixel one times size / 2.
  const double sx = 0.5 * width / reduction, sy = 0.5 * height / reduction;
  // Every Gaussian on its own, so in parallel (a serial pass here left the other threads idle
  // on every step).
  ParallelFor(static_cast<std::int64_t>(n), kStatsGrain, [&](std::int64_t j) {
    const auto i = static_cast<std::size_t>(j);
    if (radius[i] <= 0) return;
    const double gx = mean2d_grad[2 * i] * sx, gy = mean2d_grad[2 * i + 1] * sy;
    stats->grad_accum[i] += static_cast<float>(std::sqrt(gx * gx + gy * gy));
    stats->denom[i] += 1.0f;
    stats->max_radii[i] =
        std::max(stats->max_radii[i], static_cast<float>(radius[i] * reduction));
  });
}

void AccumulateMaxWeight(const std::vector<float>& view_max_weight, DensifyStats* stats) {
  HDR4D_CHECK(stats != nullptr && view_max_weight.size() == stats->max_weight.size());
  for (std::size_t i = 0; i < view_max_weight.size(); ++i)
    stats->max_weight[i] = std::max(stats->max_weight[i], view_max_weight[i]);
}

void BatchStats::Begin(std::size_t n) {
  norm_sum_.assign(n, 0.0f);
  count_.assign(n, 0.0f);
  max_radius_.assign(n, 0.0f);
}

void BatchStats::Add(const std::vector<float>& mean2d_grad,
                     const std::vector<int>& radius,
                     int width,
                     int height,
                     int reduction) {
  DensifyStats view;
  view.grad_accum = std::move(norm_sum_);
  view.denom = std::move(count_);
  view.max_radii = std::move(max_radius_);
  AccumulateStats(mean2d_grad, radius, width, height, &view, reduction);
  norm_sum_ = std::move(view.grad_accum);
  count_ = std::move(view.denom);
  max_radius_ = std::move(view.max_radii);
}

void BatchStats::AddTo(DensifyStats* stats) const {
  HDR4D_CHECK(stats != nullptr && stats->size() == count_.size() &&
              stats->grad_accum.size() == count_.size());
  for (std::size_t i = 0; i < count_.size(); ++i) {
    if (count_[i] <= 0.0f) continue;
    // sum over views of |g_v / B|, times B / count: the mean of |g_v| over the views that saw it.
    stats->grad_accum[i] += norm_sum_[i] / count_[i];
    stats->denom[i] += 1.0f;
    stats->max_radii[i] = std::max(stats->max_radii[i], max_radius_[i]);
  }
}

// ---- Clone / split / prune -----------------------------------------------------------------

std::string DensifyParams::Validate() const {
  if (!(grad_threshold >= 0.0f && std::isfinite(grad_threshold))) {
    return fmt::format("grad_threshold must be finite and >= 0, got {}", grad_threshold);
  }
  if (!(percent_dense > 0.0f && percent_dense <= 1.0f)) {
    return fmt::format("percent_dense must be in (0, 1], got {}", percent_dense);
  }
  if (!(scene_extent > 0.0f && std::isfinite(scene_extent))) {
    return fmt::format("scene_extent must be positive and finite, got {}", scene_extent);
  }
  if (!(min_opacity >= 0.0f && min_opacity < 1.0f)) {
    return fmt::format("min_opacity must be in [0, 1), got {}", min_opacity);
  }
  if (!(max_screen_size >= 0.0f && std::isfinite(max_screen_size))) {
    return fmt::format("max_screen_size must be finite and >= 0, got {}", max_screen_size);
  }
  if (!(min_contribution >= 0.0f && min_contribution < 1.0f)) {
    return fmt::format("min_contribution must be in [0, 1), got {}", min_contribution);
  }
  return "";
}

DensifyParams DensifyParamsAt(const OptimizationOptions& unresolved,
                              double extent,
                              int iteration) {
  // The trainer passes resolved options; others get the reference's image size.
  const OptimizationOptions options = unresolved.Resolved(kReferenceImageSize);
  DensifyParams p;
  p.grad_threshold = static_cast<float>(options.densify_grad_threshold);
  p.percent_dense = static_cast<float>(options.percent_dense);
  p.scene_extent = static_cast<float>(extent);
  p.min_opacity = static_cast<float>(options.prune_opacity);
  p.max_gaussians = options.max_gaussians > 0 ? static_cast<std::size_t>(options.max_gaussians) : 0;
  const bool late = iteration > options.opacity_reset_interval;
  p.max_screen_size = late ? kMaxScreenSize : 0.0f;
  p.prune_large_world = late;
  // An opacity reset leaves every opacity at 0.01, so every blending weight low until they grow
  // back: the contribution test waits as long after a reset as densification waits after the
  // start (densify_from).
  const int since_reset = iteration % options.opacity_reset_interval;
  const bool after_reset = iteration > options.opacity_reset_interval &&
                           since_reset <= options.densify_from;
  p.min_contribution = after_reset ? 0.0f : static_cast<float>(options.prune_contribution);
  p.clone_opacity_correction = options.clone_opacity_correction.value_or(false);
  return p;
}

namespace {

// The Gaussian budget: each clone or split adds one Gaussian. When n plus the candidates would
// pass max_gaussians (> 0), only the max_gaussians - n candidates with the largest mean gradient
// stay (ties: the earlier index), each list kept in index order.
void KeepWithinBudget(const std::vector<float>& mean_grad,
                      std::size_t n,
                      std::size_t max_gaussians,
                      std::vector<std::uint32_t>* clones,
                      std::vector<std::uint32_t>* parents,
                      std::vector<std::uint8_t>* is_parent) {
  const std::size_t candidates = clones->size() + parents->size();
  if (max_gaussians == 0 || n + candidates <= max_gaussians) return;
  const std::size_t allowed = max_gaussians > n ? max_gaussians - n : 0;
  std::vector<std::uint32_t> order(clones->begin(), clones->end());
  order.insert(order.end(), parents->begin(), parents->end());
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return mean_grad[a] != mean_grad[b] ? mean_grad[a] > mean_grad[b] : a < b;
  });
  std::vector<std::uint8_t> keep(n, 0);
  for (std::size_t k = 0; k < allowed; ++k) keep[order[k]] = 1;
  auto filter = [&](std::vector<std::uint32_t>* list) {
    std::erase_if(*list, [&](std::uint32_t i) { return keep[i] == 0; });
  };
  filter(clones);
  filter(parents);
  for (std::size_t i = 0; i < n; ++i) (*is_parent)[i] &= keep[i];
}

}  // namespace

namespace {

void CheckDensifyInputs(GaussianModel* model,
                        GaussianGradients* grads,
                        Adam* adam,
                        DensifyStats* stats,
                        const DensifyParams& params,
                        std::mt19937_64* rng) {
  HDR4D_CHECK(model != nullptr && grads != nullptr && adam != nullptr && stats != nullptr &&
              rng != nullptr);
  HDR4D_CHECK(params.Validate().empty());
  HDR4D_CHECK(model->Validate().empty() && FitsModel(*model, *grads));
  const std::size_t n = model->size();
  HDR4D_CHECK(n <= UINT32_MAX);  // row indices are 32-bit, as Adam's
  HDR4D_CHECK(stats->grad_accum.size() == n && stats->denom.size() == n &&
              stats->max_radii.size() == n);
  for (const GroupBuffers& g : Groups(*model, *grads)) {
    HDR4D_CHECK(adam->group(g.name).size == g.params->size());
  }
}

// The Gaussians to densify, in index order: small ones are cloned, large ones (the parents) split.
struct DensifyCandidates {
  std::vector<std::uint32_t> clones, parents;
  std::vector<std::uint8_t> is_parent;  // per Gaussian
};

DensifyCandidates SelectCandidates(const GaussianModel& model,
                                   const std::vector<float>& mean_grad,
                                   float grad_threshold,
                                   float dense_limit) {
  const std::size_t n = model.size();
  DensifyCandidates c;
  c.is_parent.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(mean_grad[i] >= grad_threshold)) continue;
    if (MaxSpatialScale(&model.log_scales[4 * i]) <= dense_limit) {
      c.clones.push_back(static_cast<std::uint32_t>(i));
    } else {
      c.parents.push_back(static_cast<std::uint32_t>(i));
      c.is_parent[i] = 1;
    }
  }
  return c;
}

// The split children's own fields, copy-major (child c of parent parents[c % parents.size()]);
// the other fields are their parent's.
struct SplitChildren {
  std::vector<float> xyz, t, log_scales;  // 3, 1 and 4 per child
};

// Child c's position (an offset drawn from the parent's Gaussian) and shrunk scales.
void DrawChild(const GaussianModel& model,
               std::size_t p,
               std::size_t c,
               NormalSampler& normal,
               SplitChildren* children) {
  const float* ls = &model.log_scales[4 * p];
  const float* mu = &model.xyz[3 * p];
  float* xyz = &children->xyz[3 * c];
  float* log_scales = &children->log_scales[4 * c];
  if (model.temporal) {
    const Vec4<double> q_l(model.rot_left[4 * p], model.rot_left[4 * p + 1],
                           model.rot_left[4 * p + 2], model.rot_left[4 * p + 3]);
    const Vec4<double> q_r(model.rot_right[4 * p], model.rot_right[4 * p + 1],
                           model.rot_right[4 * p + 2], model.rot_right[4 * p + 3]);
    Vec4<double> scaled;
    for (int k = 0; k < 4; ++k) scaled(k) = normal() * std::exp(double{ls[k]});
    const Vec4<double> offset = Rotation4D(q_l, q_r) * scaled;
    for (int k = 0; k < 3; ++k) xyz[k] = static_cast<float>(mu[k] + offset(k));
    children->t[c] = static_cast<float>(model.t[p] + offset(3));
    for (int k = 0; k < 4; ++k) log_scales[k] = ls[k] - kLogSplitShrink;
  } else {
    const Vec4<double> q(model.rot_left[4 * p], model.rot_left[4 * p + 1],
                         model.rot_left[4 * p + 2], model.rot_left[4 * p + 3]);
    Vec3<double> scaled;
    for (int k = 0; k < 3; ++k) scaled(k) = normal() * std::exp(double{ls[k]});
    const Vec3<double> offset = Rotation3D(q) * scaled;
    for (int k = 0; k < 3; ++k) xyz[k] = static_cast<float>(mu[k] + offset(k));
    children->t[c] = model.t[p];  // ignored in 3D mode: left as it was
    for (int k = 0; k < 3; ++k) log_scales[k] = ls[k] - kLogSplitShrink;
    log_scales[3] = ls[3];
  }
}

// Every child's offset is drawn, in child order, whether or not it is pruned later.
SplitChildren DrawChildren(const GaussianModel& model,
                           const std::vector<std::uint32_t>& parents,
                           std::mt19937_64* rng) {
  const std::size_t num_children = parents.size() * kSplitChildren;
  SplitChildren children;
  children.xyz.resize(num_children * 3);
  children.t.resize(num_children);
  children.log_scales.resize(num_children * 4);
  NormalSampler normal(rng);
  for (std::size_t c = 0; c < num_children; ++c)
    DrawChild(model, parents[c % parents.size()], c, normal, &children);
  return children;
}

// The rows of the new model: surviving originals, then clones (both taken from the old model by
// index), then children (indices into SplitChildren).
struct KeptRows {
  std::vector<std::uint32_t> originals, clones, children;
};

KeptRows SelectSurvivors(const GaussianModel& model,
                         const DensifyStats& stats,
                         const DensifyParams& params,
                         const DensifyCandidates& candidates,
                         const SplitChildren& children,
                         std::size_t* pruned_count) {
  const float world_limit = static_cast<float>(kLargeWorldFraction * params.scene_extent);
  // The prune test on a Gaussian with these log-scales, opacity logit and max radius.
  const bool test_radii = params.max_screen_size > 0.0f && params.keep_radii_for_prune;
  auto pruned = [&](const float* log_scales, float logit, float max_radius) {
    if (Sigmoid(logit) < params.min_opacity) return true;
    if (test_radii && max_radius > params.max_screen_size) return true;
    return params.prune_large_world && MaxSpatialScale(log_scales) > world_limit;
  };
  // Pruning by contribution: seen, never blended above the threshold, not a clone source.
  std::vector<std::uint8_t> clone_source;
  if (params.min_contribution > 0.0f) {
    HDR4D_CHECK(stats.max_weight.size() == model.size());
    clone_source.assign(model.size(), 0);
    for (std::uint32_t i : candidates.clones) clone_source[i] = 1;
  }
  const auto faint = [&](std::size_t i) {
    return params.min_contribution > 0.0f && clone_source[i] == 0 && stats.denom[i] > 0.0f &&
           stats.max_weight[i] < params.min_contribution;
  };
  KeptRows kept;
  std::size_t& count = *pruned_count;
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (candidates.is_parent[i]) continue;
    if (faint(i) ||
        pruned(&model.log_scales[4 * i], model.opacity_logit[i], stats.max_radii[i])) {
      ++count;
    } else {
      kept.originals.push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::uint32_t i : candidates.clones) {
    if (pruned(&model.log_scales[4 * i], model.opacity_logit[i], 0.0f)) {
      ++count;
    } else {
      kept.clones.push_back(i);
    }
  }
  const std::vector<std::uint32_t>& parents = candidates.parents;
  for (std::size_t c = 0; c < children.t.size(); ++c) {
    const std::uint32_t p = parents[c % parents.size()];
    if (pruned(&children.log_scales[4 * c], model.opacity_logit[p], 0.0f)) {
      ++count;
    } else {
      kept.children.push_back(static_cast<std::uint32_t>(c));
    }
  }
  return kept;
}

// Rebuilds every group's rows (and Adam's) as `kept` says, then writes the children's own fields.
// Returns the new number of Gaussians.
std::size_t RebuildModel(const KeptRows& kept,
                         const std::vector<std::uint32_t>& parents,
                         const SplitChildren& children,
                         GaussianModel* model,
                         GaussianGradients* grads,
                         Adam* adam) {
  // Old row of every appended row (children copy their parent's other fields).
  std::vector<std::uint32_t> appended = kept.clones;
  for (std::uint32_t c : kept.children) appended.push_back(parents[c % parents.size()]);
  const std::size_t first_child = kept.originals.size() + kept.clones.size();
  const std::size_t new_n = kept.originals.size() + appended.size();
  for (const GroupBuffers& g : Groups(*model, *grads)) {
    RebuildRows(g.params, kept.originals, appended, g.width);
    if (g.width > 0) {  // Adam checks row_width > 0; a 0-wide group stays empty
      adam->GatherGroup(g.name, kept.originals, g.width);
      adam->AppendRows(g.name, new_n - kept.originals.size(), g.width);
    }
  }
  for (std::size_t k = 0; k < kept.children.size(); ++k) {
    const std::size_t c = kept.children[k], row = first_child + k;
    std::copy_n(&children.xyz[3 * c], 3, &model->xyz[3 * row]);
    model->t[row] = children.t[c];
    std::copy_n(&children.log_scales[4 * c], 4, &model->log_scales[4 * row]);
  }
  return new_n;
}

}  // namespace

float HalvedCloneOpacityLogit(float logit) {
  // alpha' = 1 - s with s = sqrt(1 - alpha), so 1 - (1 - alpha')^2 = alpha. Its logit is
  // log(alpha' / s), with alpha' = alpha / (1 + s) (no cancellation for small alpha):
  // log sigmoid(l) - log1p(s) - log s, where log sigmoid(l) = -softplus(-l) and
  // log s = -softplus(l) / 2. Finite for every finite logit.
  const double l = logit;
  const double log_s = -0.5 * Softplus(l);
  return static_cast<float>(-Softplus(-l) - std::log1p(std::exp(log_s)) - log_s);
}

namespace {

// --clone-opacity-correction: each kept clone (rows after the originals) and its source, where
// the source survived, get the halved-blend opacity (a clone whose source was pruned keeps its
// own). Clone sources are never split parents. kept.originals is in index order, so a source's
// new row is its position there.
void CorrectCloneOpacities(const KeptRows& kept, GaussianModel* model) {
  const std::vector<std::uint32_t>& originals = kept.originals;
  for (std::size_t k = 0; k < kept.clones.size(); ++k) {
    const auto source = std::lower_bound(originals.begin(), originals.end(), kept.clones[k]);
    if (source == originals.end() || *source != kept.clones[k]) continue;  // pruned: stands alone
    const std::size_t clone_row = originals.size() + k;
    const float logit = HalvedCloneOpacityLogit(model->opacity_logit[clone_row]);
    model->opacity_logit[clone_row] = logit;
    model->opacity_logit[static_cast<std::size_t>(source - originals.begin())] = logit;
  }
}

}  // namespace

DensifyResult DensifyAndPrune(GaussianModel* model,
                              GaussianGradients* grads,
                              Adam* adam,
                              DensifyStats* stats,
                              const DensifyParams& params,
                              std::mt19937_64* rng) {
  CheckDensifyInputs(model, grads, adam, stats, params, rng);
  const bool colour_rows_only = ColourRowsOnly(*model, *grads);
  // Thresholds as float, as torch compares a float tensor with a Python scalar.
  const float dense_limit =
      static_cast<float>(static_cast<double>(params.percent_dense) * params.scene_extent);
  const std::vector<float> mean_grad = stats->MeanGradient();
  DensifyCandidates candidates =
      SelectCandidates(*model, mean_grad, params.grad_threshold, dense_limit);
  KeepWithinBudget(mean_grad, model->size(), params.max_gaussians, &candidates.clones,
                   &candidates.parents, &candidates.is_parent);
  const SplitChildren children = DrawChildren(*model, candidates.parents, rng);

  DensifyResult result;
  result.cloned = candidates.clones.size();
  result.split = candidates.parents.size();
  const KeptRows kept =
      SelectSurvivors(*model, *stats, params, candidates, children, &result.pruned);
  const std::size_t new_n = RebuildModel(kept, candidates.parents, children, model, grads, adam);
  if (params.clone_opacity_correction) CorrectCloneOpacities(kept, model);
  grads->ZerosLike(*model, /*colour=*/!colour_rows_only);
  BindModelGroups(*model, *grads, adam);
  stats->Reset(new_n);
  return result;
}

void ResetOpacity(GaussianModel* model, Adam* adam, float max_opacity) {
  HDR4D_CHECK(model != nullptr && adam != nullptr);
  HDR4D_CHECK(max_opacity > 0.0f && max_opacity < 1.0f);
  const double p = max_opacity;
  const float max_logit = static_cast<float>(std::log(p / (1.0 - p)));
  for (float& logit : model->opacity_logit) logit = std::min(logit, max_logit);
  adam->ResetMoments(kGroupOpacity);
}

}  // namespace hdr4d::method
