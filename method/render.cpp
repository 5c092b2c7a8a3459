#include "method/render.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "core/error.h"
#include "core/parallel.h"
#include "method/constants.h"
#include "method/preprocess_simd.h"
#include "method/raster/binning.h"
#include "method/raster/blend.h"
#include "method/rotation4d.h"
#include "method/sh4d.h"
#include "method/slice.h"

namespace hdr4d::method {
namespace {

constexpr std::int64_t kGaussianGrain = 1024;
constexpr std::int64_t kRowsDoneBlock = 256;

template <typename T>
Vec4<T> Row4(const std::vector<T>& v, std::size_t i) {
  return Vec4<T>(v[i * 4], v[i * 4 + 1], v[i * 4 + 2], v[i * 4 + 3]);
}

template <typename T>
T Sigmoid(T x) {
  return T(1) / (T(1) + std::exp(-x));
}

template <typename T>
Vec4<T> Mean4(const GaussianModelT<T>& model, std::size_t i) {
  return Vec4<T>(model.xyz[i * 3], model.xyz[i * 3 + 1], model.xyz[i * 3 + 2], model.t[i]);
}

template <typename T>
ConditionalGaussian<T> ConditionAt(const GaussianModelT<T>& model, std::size_t i, T time) {
  ConditionalGaussian<T> c;
  const Vec4<T> mean4 = Mean4(model, i);
  const Vec4<T> log_scales = Row4(model.log_scales, i);
  if (model.temporal) {
    c.rotation4 = Rotation4D(Row4(model.rot_left, i), Row4(model.rot_right, i));
    c.sigma4 = Covariance4D(c.rotation4, log_scales);
    const Slice<T> slice = SliceAtTime(mean4, c.sigma4, time);
    c.mean = slice.mean;
    c.cov = slice.cov;
    c.marginal = slice.marginal;
  } else {
    c.rotation3 = Rotation3D(Row4(model.rot_left, i));
    c.cov = Covariance3D(c.rotation3, Vec3<T>(log_scales.template head<3>()));
    c.mean = mean4.template head<3>();
  }
  return c;
}

template <typename T>
int TimeDegree(const GaussianModelT<T>& model, const RenderOptions& options) {
  return model.temporal ? std::min(options.time_degree, model.basis.max_time_degree) : 0;
}

constexpr int kMaxChannels = 8;

// The radius the tiles are binned with: the 3-sigma screen radius, tightened to where
// opacity x G can still reach the blending threshold 1/255 (G = exp(-d^2 / (2 lambda)) along the
// widest axis), so tiles the splat cannot touch get no entry. Pixels outside it have
// alpha < 1/255 and are skipped by the blend anyway: images and gradients are unchanged.
template <typename T>
int BinningRadius(const Splat2D<T>& splat, T opacity) {
  const T reach = opacity * T(255);
  if (!(reach > T(1))) return 0;  // can never reach 1/255 anywhere
  const T mid = T(0.5) * (splat.cov2d[0] + splat.cov2d[2]);
  const T det = splat.cov2d[0] * splat.cov2d[2] - splat.cov2d[1] * splat.cov2d[1];
  const T lambda = mid + std::sqrt(std::max(T(0.1), mid * mid - det));
  const T r = std::sqrt(T(2) * std::log(reach) * lambda);
  return std::min(splat.radius, static_cast<int>(std::ceil(r)) + 1);  // +1: rounding margin
}

// Clears Gaussian i's gradient rows; the colour rows only when asked (a visible Gaussian's
// colour rows are overwritten in full by the backward).
template <typename T>
void ZeroRows(GaussianGradientsT<T>* g, std::size_t i, bool colour) {
  std::fill_n(&g->xyz[i * 3], 3, T(0));
  g->t[i] = T(0);
  std::fill_n(&g->log_scales[i * 4], 4, T(0));
  std::fill_n(&g->rot_left[i * 4], 4, T(0));
  std::fill_n(&g->rot_right[i * 4], 4, T(0));
  g->opacity_logit[i] = T(0);
  if (!colour) return;
  std::fill_n(&g->color_dc[i * g->channels], g->channels, T(0));
  const std::size_t rest = g->rest_stride();
  std::fill_n(&g->color_rest[i * rest], rest, T(0));
}

// colour[c] = kColorOffset + sum over the active coefficients k of w[k] coef_k[c] (coefficient 0
// from dc, k >= 1 from rest at (k - 1) * channels). The inactive ones have w = 0.
template <typename T>
void ColorFromWeights(const T* w,
                      const T* dc,
                      const T* rest,
                      int channels,
                      int functions,
                      int active,
                      int time_degree,
                      T* color) {
  for (int ch = 0; ch < channels; ++ch) color[ch] = static_cast<T>(kColorOffset) + w[0] * dc[ch];
  for (int n = 0; n <= time_degree; ++n) {
    for (int lm = n == 0 ? 1 : 0; lm < active; ++lm) {
      const int k = n * functions + lm;
      const T* ck = rest + (k - 1) * channels;
      for (int ch = 0; ch < channels; ++ch) color[ch] += w[k] * ck[ch];
    }
  }
}

// Three channels in float, the common case: a coefficient's 3 values as one 4-lane vector (the
// 4th lane is the next coefficient's and ignored), in 4 independent accumulators. The scalar loop
// above kept the colour in memory (it may alias) and was a third of the whole preprocess.
using Float4 = float __attribute__((vector_size(16)));
inline Float4 Load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
inline Float4 Load3(const float* p) { return Float4{p[0], p[1], p[2], 0.0f}; }

inline void ColorFromWeights3(const float* w,
                              const float* dc,
                              const float* rest,
                              int functions,
                              int active,
                              int time_degree,
                              int coefficients,
                              float* color) {
  Float4 acc0 = Load3(dc) * w[0], acc1 = {}, acc2 = {}, acc3 = {};
  const auto term = [&](int k) {
    // The last coefficient of the row has no 4th float after it.
    const float* ck = rest + (k - 1) * 3;
    return (k + 1 < coefficients ? Load4(ck) : Load3(ck)) * w[k];
  };
  for (int n = 0; n <= time_degree; ++n) {
    const int end = n * functions + active;
    int k = n * functions + (n == 0 ? 1 : 0);
    for (; k + 4 <= end; k += 4) {
      acc0 += term(k);
      acc1 += term(k + 1);
      acc2 += term(k + 2);
      acc3 += term(k + 3);
    }
    for (; k < end; ++k) acc1 += term(k);
  }
  const Float4 sum = (acc0 + acc1) + (acc2 + acc3);
  for (int ch = 0; ch < 3; ++ch) color[ch] = static_cast<float>(kColorOffset) + sum[ch];
}

template <typename T>
void Color(const T* w,
           const T* dc,
           const T* rest,
           int channels,
           const ColorBasis& basis,
           int sh_degree,
           int time_degree,
           T* color) {
  const int functions = basis.sh_functions();
  const int active = (sh_degree + 1) * (sh_degree + 1);
  if constexpr (std::is_same_v<T, float>) {
    if (channels == 3) {
      return ColorFromWeights3(w, dc, rest, functions, active, time_degree, basis.coefficients(),
                               color);
    }
  }
  ColorFromWeights(w, dc, rest, channels, functions, active, time_degree, color);
}

// The colour rows' gradient, written for every coefficient (w = 0 for the inactive ones).
template <typename T>
void ColorGradRows(const T* w, const T* dcolor, int channels, int coefficients, T* gdc, T* grest) {
  if constexpr (std::is_same_v<T, float>) {
    if (channels == 3) {
      const Float4 d = Load3(dcolor);
      for (int ch = 0; ch < 3; ++ch) gdc[ch] = w[0] * dcolor[ch];
      // Overlapping 4-float stores, each 4th lane overwritten by the next; the last row of 3
      // is stored alone (it ends the Gaussian's row).
      int k = 1;
      for (; k + 1 < coefficients; ++k) {
        const Float4 g = d * w[k];
        std::memcpy(grest + (k - 1) * 3, &g, sizeof(g));
      }
      if (k < coefficients) {
        for (int ch = 0; ch < 3; ++ch) grest[(k - 1) * 3 + ch] = w[k] * dcolor[ch];
      }
      return;
    }
  }
  for (int ch = 0; ch < channels; ++ch) gdc[ch] = w[0] * dcolor[ch];
  for (int k = 1; k < coefficients; ++k) {
    for (int ch = 0; ch < channels; ++ch) grest[(k - 1) * channels + ch] = w[k] * dcolor[ch];
  }
}

constexpr int kColorAhead = 8;
template <typename T>
void PrefetchRow(const T* row, std::size_t count) {
  const char* p = reinterpret_cast<const char*>(row);
  for (std::size_t b = 0; b < count * sizeof(T); b += 64) __builtin_prefetch(p + b);
}

template <typename T>
void CheckInputs(const GaussianModelT<T>& model, const RenderOptions& options) {
  HDR4D_CHECK(model.Validate().empty());
  HDR4D_CHECK(model.channels <= kMaxChannels);
  HDR4D_CHECK(options.sh_degree >= 0 && options.sh_degree <= model.basis.max_sh_degree);
  HDR4D_CHECK(options.time_degree >= 0);
  const int features =
      options.color_stage ? options.color_stage->feature_channels() : model.channels;
  HDR4D_CHECK(features <= kMaxChannels);
  HDR4D_CHECK(options.background.empty() ||
              static_cast<int>(options.background.size()) == features);
}

RasterSettings SettingsFor(const Camera& camera, const RenderOptions& options, int channels) {
  RasterSettings settings;
  settings.width = camera.intrinsics.width;
  settings.height = camera.intrinsics.height;
  settings.background =
      options.background.empty() ? std::vector<float>(channels, 0.0f) : options.background;
  settings.backend = options.backend;
  return settings;
}

// The float 4D path vectorised over Gaussians (preprocess_simd.h) with the SIMD blend backend;
// the scalar backend, double and 3D mode keep the generic per-Gaussian code.
template <typename T>
bool UseSimdPreprocess(const GaussianModelT<T>& model, const RenderOptions& options) {
  return std::is_same_v<T, float> && model.temporal && options.backend == RasterBackend::kSimd;
}

internal::PreprocessSimdJob MakePreprocessJob(const GaussianModel& model,
                                              const ViewParams<float>& view,
                                              float time,
                                              const RenderOptions& options) {
  internal::PreprocessSimdJob job;
  job.xyz = model.xyz.data();
  job.t = model.t.data();
  job.log_scales = model.log_scales.data();
  job.rot_left = model.rot_left.data();
  job.rot_right = model.rot_right.data();
  job.opacity_logit = model.opacity_logit.data();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) job.rotation[3 * r + c] = view.rotation(r, c);
    job.translation[r] = view.translation[r];
  }
  job.fx = view.fx;
  job.fy = view.fy;
  job.cx = view.cx;
  job.cy = view.cy;
  job.lim_x = kFrustumTanMargin * view.TanFovX();
  job.lim_y = kFrustumTanMargin * view.TanFovY();
  const Vec3<float> center = view.Center();
  for (int k = 0; k < 3; ++k) job.center[k] = center[k];
  job.time = time;
  job.duration = options.time_duration;
  job.sh_degree = options.sh_degree;
  job.time_degree = TimeDegree(model, options);
  job.functions = model.basis.sh_functions();
  job.coefficients = model.basis.coefficients();
  detail::CheckColorDegrees(model.basis, job.sh_degree, job.time_degree);
  HDR4D_CHECK(job.time_degree == 0 || job.duration > 0.0f);
  return job;
}

// One lane's weights out of a batch's [k][lane] block.
inline void LaneWeights(const float* batch, int lane, int coefficients, float* w) {
  for (int k = 0; k < coefficients; ++k) w[k] = batch[k * internal::kPreprocessBatch + lane];
}

}  // namespace

template <typename T>
void PreprocessForward(const GaussianModelT<T>& model,
                       const ViewParams<T>& view,
                       T time,
                       const RenderOptions& options,
                       FrameStateT<T>* state) {
  CheckInputs(model, options);
  const std::size_t n = model.size();
  const int channels = model.channels;
  SplatBuffersT<T>& s = state->splats;
  ColorStage* const stage = options.color_stage;
  HDR4D_CHECK(stage == nullptr ||
              (std::is_same_v<T, float> && model.color_mode == ColorMode::kLogHdr));
  s.channels = stage ? stage->feature_channels() : channels;
  s.Resize(n);
  if (stage) state->colors.resize(n * channels);
  state->clamped.assign(n * channels, 0);
  state->conditionals.resize(n);  // written for visible Gaussians only
  state->screen_radius.assign(n, 0);
  const Vec3<T> center = view.Center();
  const int time_degree = TimeDegree(model, options);
  const std::size_t stride = model.rest_stride();
  const T duration = static_cast<T>(options.time_duration);
  std::vector<std::int64_t> visible_per_chunk((n + kGaussianGrain - 1) / kGaussianGrain, 0);
  if constexpr (std::is_same_v<T, float>) {
    if (UseSimdPreprocess(model, options)) {
      internal::PreprocessSimdJob job = MakePreprocessJob(model, view, time, options);
      job.mean2d = s.mean2d.data();
      job.conic = s.conic.data();
      job.depth = s.depth.data();
      job.opacity = s.opacity.data();
      job.radius = s.radius.data();
      job.screen_radius = state->screen_radius.data();
      const int coefficients = job.coefficients;
      ParallelForChunks(
          static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t b, std::int64_t e) {
            alignas(64) float batch_w[kMaxColorCoefficients * internal::kPreprocessBatch];
            float w[kMaxColorCoefficients];
            std::int64_t visible = 0;
            for (std::int64_t g0 = b; g0 < e; g0 += internal::kPreprocessBatch) {
              const int count =
                  static_cast<int>(std::min<std::int64_t>(internal::kPreprocessBatch, e - g0));
              internal::PreprocessForwardSimd(job, g0, count, batch_w);
              for (int l = 0; l < count; ++l) {
                const std::size_t i = static_cast<std::size_t>(g0 + l);
                // The colour rows stream from memory (the optimiser's sweep evicts them).
                if (stride > 0 && g0 + l + kColorAhead < e)
                  PrefetchRow(&model.color_rest[(i + kColorAhead) * stride], stride);
                if (state->screen_radius[i] == 0) continue;
                LaneWeights(batch_w, l, coefficients, w);
                float* color = stage ? &state->colors[i * channels] : &s.features[i * channels];
                Color(w, &model.color_dc[i * channels], &model.color_rest[i * stride], channels,
                      model.basis, options.sh_degree, time_degree, color);
                if (model.color_mode == ColorMode::kLdr) {
                  for (int ch = 0; ch < channels; ++ch) {
                    if (color[ch] < 0.0f) {
                      color[ch] = 0.0f;
                      state->clamped[i * channels + ch] = 1;
                    }
                  }
                }
                ++visible;
              }
            }
            visible_per_chunk[b / kGaussianGrain] = visible;
          });
    }
  }
  if (!UseSimdPreprocess(model, options)) {
    ParallelForChunks(
        static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t b, std::int64_t e) {
          std::int64_t visible = 0;
          for (std::int64_t g = b; g < e; ++g) {
            const std::size_t i = static_cast<std::size_t>(g);
            // The colour rows stream from memory (the optimiser's sweep evicts them):
            // fetch a few Gaussians ahead.
            if (stride > 0 && g + kColorAhead < e)
              PrefetchRow(&model.color_rest[(i + kColorAhead) * stride], stride);
            s.radius[i] = 0;
            const ConditionalGaussian<T> c = ConditionAt(model, i, time);
            if (model.temporal && !TemporallyVisible(c.marginal))
              continue;  // culled: costs nothing
            const Splat2D<T> splat = ProjectEwa(c.mean, c.cov, view);
            if (!splat.visible) continue;
            s.mean2d[2 * i] = splat.mean.x();
            s.mean2d[2 * i + 1] = splat.mean.y();
            for (int k = 0; k < 3; ++k) s.conic[3 * i + k] = splat.conic[k];
            s.depth[i] = splat.depth;
            s.opacity[i] = Sigmoid(model.opacity_logit[i]) * c.marginal;
            state->screen_radius[i] = splat.radius;
            s.radius[i] = BinningRadius(splat, s.opacity[i]);
            state->conditionals[i] = c;  // the backward reuses it
            // Colour is linear in the coefficients: weights . (DC, rest) + 0.5.
            T w[kMaxColorCoefficients];
            EvalColorBasisWeights(Vec3<T>(c.mean - center), model.t[i] - time, duration,
                                  model.basis, options.sh_degree, time_degree, w);
            T* color = stage ? &state->colors[i * channels] : &s.features[i * channels];
            Color(w, &model.color_dc[i * channels], &model.color_rest[i * stride], channels,
                  model.basis, options.sh_degree, time_degree, color);
            if (model.color_mode == ColorMode::kLdr) {
              for (int ch = 0; ch < channels; ++ch) {
                if (color[ch] < T(0)) {
                  color[ch] = T(0);
                  state->clamped[i * channels + ch] = 1;
                }
              }
            }
            ++visible;
          }
          visible_per_chunk[b / kGaussianGrain] = visible;
        });
  }
  state->num_visible = 0;
  for (std::int64_t v : visible_per_chunk) state->num_visible += static_cast<std::size_t>(v);
  if (stage) {
    state->visible.clear();
    state->visible.reserve(state->num_visible);
    for (std::size_t i = 0; i < n; ++i) {
      if (s.radius[i] > 0) state->visible.push_back(static_cast<std::uint32_t>(i));
    }
    if constexpr (std::is_same_v<T, float>) {
      stage->Forward(state->colors.data(), channels, state->visible, s.features.data());
    }
  }
}

template <typename T>
void PreprocessBackward(const GaussianModelT<T>& model,
                        const ViewParams<T>& view,
                        T time,
                        const RenderOptions& options,
                        const FrameStateT<T>& state,
                        GaussianGradientsT<T>* grads,
                        const GradientRowsDoneT<T>& rows_done) {
  const std::size_t n = model.size();
  HDR4D_CHECK(grads->size() == n && grads->color_rest.size() == model.color_rest.size());
  const int channels = model.channels;
  const SplatBuffersT<T>& s = state.splats;
  const SplatGradientsT<T>& sg = state.splat_grads;
  HDR4D_CHECK(sg.opacity.size() == n && state.conditionals.size() == n);
  const Vec3<T> center = view.Center();
  const int time_degree = TimeDegree(model, options);
  const std::size_t stride = model.rest_stride();
  const int num_coefficients = model.basis.coefficients();
  const T duration = static_cast<T>(options.time_duration);
  if constexpr (std::is_same_v<T, float>) {
    if (UseSimdPreprocess(model, options)) {
      internal::PreprocessSimdJob job = MakePreprocessJob(model, view, time, options);
      job.radius_in = s.radius.data();
      job.g_mean2d = sg.mean2d.data();
      job.g_conic = sg.conic.data();
      job.g_opacity = sg.opacity.data();
      job.d_xyz = grads->xyz.data();
      job.d_t = grads->t.data();
      job.d_log_scales = grads->log_scales.data();
      job.d_rot_left = grads->rot_left.data();
      job.d_rot_right = grads->rot_right.data();
      job.d_opacity_logit = grads->opacity_logit.data();
      ParallelForChunks(
          static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t b, std::int64_t e) {
            alignas(64) float batch_w[kMaxColorCoefficients * internal::kPreprocessBatch];
            float w[kMaxColorCoefficients];
            std::int64_t done = b;  // rows before this are handed to rows_done
            // With rows_done the colour rows (nine tenths of the gradient) go to a per-thread
            // block that is handed over and reused, so they never travel to memory and back.
            thread_local std::vector<float> block_dc, block_rest;
            if (rows_done) {
              block_dc.resize(
                  static_cast<std::size_t>(kRowsDoneBlock + internal::kPreprocessBatch) * channels);
              block_rest.resize(
                  static_cast<std::size_t>(kRowsDoneBlock + internal::kPreprocessBatch) * stride);
            }
            for (std::int64_t g0 = b; g0 < e; g0 += internal::kPreprocessBatch) {
              const int count =
                  static_cast<int>(std::min<std::int64_t>(internal::kPreprocessBatch, e - g0));
              internal::PreprocessBackwardSimd(job, g0, count, batch_w);
              for (int l = 0; l < count; ++l) {
                const std::size_t i = static_cast<std::size_t>(g0 + l);
                const std::size_t row = rows_done ? i - static_cast<std::size_t>(done) : i;
                float* gdc = rows_done ? &block_dc[row * channels] : &grads->color_dc[i * channels];
                float* grest =
                    rows_done ? &block_rest[row * stride] : &grads->color_rest[i * stride];
                if (s.radius[i] <= 0) {
                  std::fill_n(gdc, channels, 0.0f);
                  std::fill_n(grest, stride, 0.0f);
                  continue;
                }
                float dcolor[kMaxChannels];
                const float* dfeatures = options.color_stage ? &state.color_grads[i * channels]
                                                             : &sg.features[i * channels];
                for (int ch = 0; ch < channels; ++ch)
                  dcolor[ch] = state.clamped[i * channels + ch] ? 0.0f : dfeatures[ch];
                LaneWeights(batch_w, l, num_coefficients, w);
                ColorGradRows(w, dcolor, channels, num_coefficients, gdc, grest);
              }
              // Blocks of kRowsDoneBlock rows: ~160 KB of gradients at 160 floats a row, still in
              // L2.
              const std::int64_t next = g0 + count;
              if (rows_done && (next - done >= kRowsDoneBlock || next == e)) {
                rows_done(done, next, GradientRows{block_dc.data(), block_rest.data()});
                done = next;
              }
            }
          });
      return;
    }
  }
  ParallelFor(static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t g) {
    const std::size_t i = static_cast<std::size_t>(g);
    // Every row is written here (zeros for a culled Gaussian), so the caller needs no separate
    // pass that clears 160 floats per Gaussian before each backward.
    const bool visible = s.radius[i] > 0;
    ZeroRows(grads, i, !visible);
    if (!visible) return;
    const ConditionalGaussian<T>& c = state.conditionals[i];

    // Colour: the view direction and dt are detached, as in the reference.
    T dcolor[kMaxChannels];
    const T* dfeatures =
        options.color_stage ? &state.color_grads[i * channels] : &sg.features[i * channels];
    for (int ch = 0; ch < channels; ++ch) {
      dcolor[ch] = state.clamped[i * channels + ch] ? T(0) : dfeatures[ch];
    }
    T w[kMaxColorCoefficients];
    EvalColorBasisWeights(Vec3<T>(c.mean - center), model.t[i] - time, duration, model.basis,
                          options.sh_degree, time_degree, w);
    T* gdc = &grads->color_dc[i * channels];
    T* grest = &grads->color_rest[i * stride];
    // Written, not accumulated: every colour row in one pass (w is 0 for inactive degrees).
    ColorGradRows(w, dcolor, channels, num_coefficients, gdc, grest);

    // Opacity = sigmoid(logit) x marginal.
    const T sig = Sigmoid(model.opacity_logit[i]);
    grads->opacity_logit[i] += sg.opacity[i] * c.marginal * sig * (T(1) - sig);
    const T dmarginal = sg.opacity[i] * sig;

    Vec3<T> dmean3;
    Mat3<T> dcov3;
    ProjectEwaBackward(c.mean, c.cov, view, Vec2<T>(sg.mean2d[2 * i], sg.mean2d[2 * i + 1]),
                       Vec3<T>(sg.conic[3 * i], sg.conic[3 * i + 1], sg.conic[3 * i + 2]), &dmean3,
                       &dcov3);
    const Vec4<T> log_scales = Row4(model.log_scales, i);
    if (model.temporal) {
      Vec4<T> dmean4;
      Mat4<T> dsigma;
      SliceAtTimeBackward(Mean4(model, i), c.sigma4, time, dmean3, dcov3, dmarginal, &dmean4,
                          &dsigma);
      Mat4<T> drot;
      Vec4<T> dlog_scales;
      Covariance4DBackward(c.rotation4, log_scales, dsigma, &drot, &dlog_scales);
      Vec4<T> dql, dqr;
      Rotation4DBackward(Row4(model.rot_left, i), Row4(model.rot_right, i), drot, &dql, &dqr);
      for (int k = 0; k < 3; ++k) grads->xyz[i * 3 + k] += dmean4[k];
      grads->t[i] += dmean4[3];
      for (int k = 0; k < 4; ++k) {
        grads->log_scales[i * 4 + k] += dlog_scales[k];
        grads->rot_left[i * 4 + k] += dql[k];
        grads->rot_right[i * 4 + k] += dqr[k];
      }
    } else {
      Mat3<T> drot;
      Vec3<T> dlog_scales;
      Covariance3DBackward(c.rotation3, Vec3<T>(log_scales.template head<3>()), dcov3, &drot,
                           &dlog_scales);
      Vec4<T> dq;
      Rotation3DBackward(Row4(model.rot_left, i), drot, &dq);
      for (int k = 0; k < 3; ++k) {
        grads->xyz[i * 3 + k] += dmean3[k];
        grads->log_scales[i * 4 + k] += dlog_scales[k];
      }
      for (int k = 0; k < 4; ++k) grads->rot_left[i * 4 + k] += dq[k];
    }
  });
  if (rows_done) {
    ParallelForChunks(
        static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t b, std::int64_t e) {
          const std::size_t i = static_cast<std::size_t>(b);
          rows_done(
              b, e,
              GradientRowsT<T>{&grads->color_dc[i * channels], &grads->color_rest[i * stride]});
        });
  }
}

void RenderForward(const GaussianModel& model,
                   const Camera& camera,
                   float time,
                   const RenderOptions& options,
                   FrameState* state,
                   float* image) {
  const ViewParams<float> view = ViewParams<float>::FromCamera(camera);
  PreprocessForward(model, view, time, options, state);
  RasterizeForward(state->splats, SettingsFor(camera, options, state->splats.channels),
                   &state->raster, image);
}

void RenderBackward(const GaussianModel& model,
                    const Camera& camera,
                    float time,
                    const RenderOptions& options,
                    FrameState* state,
                    const float* dL_dimage,
                    GaussianGradients* grads,
                    const GradientRowsDone& rows_done) {
  const int features = state->splats.channels;
  state->splat_grads.SetZero(model.size(), features);
  BlendBackward(state->splats, SettingsFor(camera, options, features), &state->raster, dL_dimage,
                nullptr, &state->splat_grads, nullptr);
  if (ColorStage* stage = options.color_stage) {
    state->color_grads.resize(model.size() * model.channels);
    stage->Backward(state->colors.data(), model.channels, state->visible,
                    state->splat_grads.features.data(), state->color_grads.data());
  }
  PreprocessBackward(model, ViewParams<float>::FromCamera(camera), time, options, *state, grads,
                     rows_done);
}

template <typename T>
void RenderForwardReference(const GaussianModelT<T>& model,
                            const Camera& camera,
                            T time,
                            const RenderOptions& options,
                            FrameStateT<T>* state,
                            T* image) {
  const ViewParams<T> view = ViewParams<T>::FromCamera(camera);
  PreprocessForward(model, view, time, options, state);
  const RasterSettings settings = SettingsFor(camera, options, model.channels);
  BinSplats(state->splats, settings, &state->raster);
  const std::vector<T> background(settings.background.begin(), settings.background.end());
  const std::size_t pixels = static_cast<std::size_t>(settings.width) * settings.height;
  state->final_T.resize(pixels);
  state->n_contrib.resize(pixels);
  BlendForwardReference(state->splats, state->raster, background.data(), image,
                        state->final_T.data(), state->n_contrib.data());
}

template <typename T>
void RenderBackwardReference(const GaussianModelT<T>& model,
                             const Camera& camera,
                             T time,
                             const RenderOptions& options,
                             FrameStateT<T>* state,
                             const T* dL_dimage,
                             GaussianGradientsT<T>* grads) {
  const RasterSettings settings = SettingsFor(camera, options, model.channels);
  const std::vector<T> background(settings.background.begin(), settings.background.end());
  state->splat_grads.SetZero(model.size(), model.channels);
  BlendBackwardReference(state->splats, state->raster, background.data(), state->final_T.data(),
                         state->n_contrib.data(), dL_dimage, static_cast<const T*>(nullptr),
                         &state->splat_grads, static_cast<T*>(nullptr));
  PreprocessBackward(model, ViewParams<T>::FromCamera(camera), time, options, *state, grads);
}

#define HDR4D_INSTANTIATE_RENDER(T)                                                      \
  template void PreprocessForward(const GaussianModelT<T>&, const ViewParams<T>&, T,     \
                                  const RenderOptions&, FrameStateT<T>*);                \
  template void PreprocessBackward(const GaussianModelT<T>&, const ViewParams<T>&, T,    \
                                   const RenderOptions&, const FrameStateT<T>&,          \
                                   GaussianGradientsT<T>*, const GradientRowsDoneT<T>&); \
  template void RenderForwardReference(const GaussianModelT<T>&, const Camera&, T,       \
                                       const RenderOptions&, FrameStateT<T>*, T*);       \
  template void RenderBackwardReference(const GaussianModelT<T>&, const Camera&, T,      \
                                        const RenderOptions&, FrameStateT<T>*, const T*, \
                                        GaussianGradientsT<T>*);
HDR4D_INSTANTIATE_RENDER(float)
HDR4D_INSTANTIATE_RENDER(double)
#undef HDR4D_INSTANTIATE_RENDER

}  // namespace hdr4d::method
