// The fast preprocess (preprocess.h): float, 4D or 3D, the Highway kernels of preprocess_simd.h over
// batches of Gaussians, the colour sums per Gaussian (preprocess_common.h). The forward's full
// geometry runs only on the Gaussians a cheap test by time keeps, the backward's only on the
// visible ones: in a dynamic scene most are culled by time (70% at the paper's Syn configuration).
#include <algorithm>
#include <utility>
#include <vector>

#include "core/util/parallel.h"
#include "method/render/preprocess.h"
#include "method/render/preprocess_common.h"
#include "method/render/preprocess_simd.h"

namespace hdr4d::method {
namespace detail {

PreprocessSimdJob MakePreprocessJob(const GaussianModel& model,
                                    const ViewParams<float>& view,
                                    float time,
                                    const RenderOptions& options) {
  PreprocessSimdJob job;
  job.temporal = model.temporal;
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
  job.used_coefficients = model.basis.used_coefficients(job.sh_degree, job.time_degree);
  detail::CheckColorDegrees(model.basis, job.sh_degree, job.time_degree);
  HDR4D_CHECK(job.time_degree == 0 || job.duration > 0.0f);
  return job;
}

}  // namespace detail

using namespace detail;
namespace {

// One lane's weights out of a batch's [k][lane] block.
inline void LaneWeights(const float* batch, int lane, int coefficients, float* w) {
  for (int k = 0; k < coefficients; ++k) w[k] = batch[k * kPreprocessBatch + lane];
}

// The geometry gradients of Gaussian i, zero (what the kernel writes for a culled Gaussian).
void ZeroGeometryGradients(std::size_t i, GaussianGradients* grads) {
  std::fill_n(&grads->xyz[3 * i], 3, 0.0f);
  grads->t[i] = 0.0f;
  std::fill_n(&grads->log_scales[4 * i], 4, 0.0f);
  std::fill_n(&grads->rot_left[4 * i], 4, 0.0f);
  std::fill_n(&grads->rot_right[4 * i], 4, 0.0f);
  grads->opacity_logit[i] = 0.0f;
}

}  // namespace

void PreprocessForwardFast(const GaussianModel& model,
                           const ViewParams<float>& view,
                           float time,
                           const RenderOptions& options,
                           FrameState* state) {
  BeginPreprocess(model, options, state);
  // The fast path keeps no conditional Gaussians (216 bytes each, resident once written): its
  // backward recomputes what it needs. Give back what a reference frame left.
  if (!state->conditionals.empty())
    std::vector<ConditionalGaussian<float>>().swap(state->conditionals);
  const std::size_t n = model.size();
  SplatBuffersT<float>& s = state->splats;
  const int time_degree = TimeDegree(model, options);
  const std::size_t stride = model.rest_stride();
  std::vector<std::int64_t> visible_per_chunk((n + kGaussianGrain - 1) / kGaussianGrain, 0);
  PreprocessSimdJob job = MakePreprocessJob(model, view, time, options);
  job.mean2d = s.mean2d.data();
  job.conic = s.conic.data();
  job.depth = s.depth.data();
  job.opacity = s.opacity.data();
  job.radius = s.radius.data();
  job.reach = s.reach.data();
  job.screen_radius = state->screen_radius.data();
  // Only the coefficients the colour degrees use are read, so only their part of each row is
  // gathered and prefetched (none of the rest rows at SH and time degree 0).
  const int used = job.used_coefficients;
  const std::size_t used_rest = static_cast<std::size_t>(used - 1) * model.channels;
  const auto chunk = [&](std::int64_t b, std::int64_t e) {
    // The Gaussians culled by time alone are done here, without their geometry.
    HDR4D_CHECK(e - b <= kGaussianGrain);
    std::int64_t survivors[kGaussianGrain];
    const int num_survivors =
        PreprocessTemporalSurvivors(job, b, static_cast<int>(e - b), survivors);
    // The colour rows stream from memory (the optimiser's sweep evicts them): every row of the
    // chunk is prefetched in order, kColorAhead rows ahead of the survivor being coloured. In
    // order and with the culled Gaussians' rows too: prefetching only the survivors' rows left
    // gaps in the stream, and colouring took twice as long (perf, a render of a dynamic model).
    std::int64_t next_prefetch = b;
    const auto prefetch_to = [&](std::int64_t last) {
      for (last = std::min(last, e - 1); next_prefetch <= last && used_rest > 0; ++next_prefetch)
        PrefetchRow(&model.color_rest[static_cast<std::size_t>(next_prefetch) * stride],
                    used_rest);
    };
    alignas(64) float batch_w[kMaxColorCoefficients * kPreprocessBatch];
    float w[kMaxColorCoefficients];
    std::int64_t visible = 0;
    for (int k = 0; k < num_survivors; k += kPreprocessBatch) {
      const int count = std::min(kPreprocessBatch, num_survivors - k);
      PreprocessForwardSimd(job, survivors + k, count, batch_w);
      for (int l = 0; l < count; ++l) {
        prefetch_to(survivors[k + l] + kColorAhead);
        const std::size_t i = static_cast<std::size_t>(survivors[k + l]);
        if (state->screen_radius[i] == 0) continue;
        LaneWeights(batch_w, l, used, w);
        WriteColour(model, i, w, options, time_degree, state);
        ++visible;
      }
    }
    visible_per_chunk[b / kGaussianGrain] = visible;
  };
  ParallelForChunks(static_cast<std::int64_t>(n), kGaussianGrain, chunk);
  FinishPreprocess(options, model, visible_per_chunk, state);
}

namespace {

// With rows_done the colour rows (nine tenths of the gradient) go to a per-thread block of
// kRowsDoneBlock rows that is handed over and reused, so they never travel to memory and back.
struct ColourRowBlock {
  std::vector<float> dc, rest;
  // Which block rows already hold zeros (a culled Gaussian's, and not written since): in a
  // dynamic scene most Gaussians are culled by time, and re-zeroing their ~600-byte rows on
  // every use of the block was 1.6% of a paper-configuration iteration. A block of another
  // size (another layout) starts all zeros.
  std::vector<char> row_is_zero;
  // Every rest row is zero from coefficient `written` on: a row is written only up to the
  // coefficients the colour degrees use (they only grow in a run), or up to `written` where that
  // is further, so that no earlier, longer row's tail is left behind. While the degrees are low
  // this skips most of a row (45 of 48 floats at SH degree 0), and the optimiser reads only the
  // active columns (AdamRowStep::LimitColumns).
  int written = 1;
  void Fit(int channels, std::size_t stride) {
    const std::size_t dc_size = static_cast<std::size_t>(kRowsDoneBlock) * channels;
    const std::size_t rest_size = static_cast<std::size_t>(kRowsDoneBlock) * stride;
    if (dc.size() == dc_size && rest.size() == rest_size) return;
    dc.assign(dc_size, 0.0f);
    rest.assign(rest_size, 0.0f);
    row_is_zero.assign(kRowsDoneBlock, 1);
    written = 1;
  }
};

// The fast backward over chunks of Gaussians, each cut into blocks of kRowsDoneBlock rows
// (~160 KB of gradients at 160 floats a row, still in L2) handed to rows_done when it is set.
class FastBackward {
 public:
  FastBackward(const GaussianModel& model,
               const ViewParams<float>& view,
               float time,
               const RenderOptions& options,
               const FrameState& state,
               GaussianGradients* grads,
               const GradientRowsDone& rows_done)
      : model_(model),
        options_(options),
        state_(state),
        grads_(grads),
        rows_done_(rows_done),
        job_(MakePreprocessJob(model, view, time, options)) {
    const SplatGradientsT<float>& sg = state.splat_grads;
    job_.radius_in = state.splats.radius.data();
    job_.g_mean2d = sg.mean2d.data();
    job_.g_conic = sg.conic.data();
    job_.g_opacity = sg.opacity.data();
    job_.d_xyz = grads->xyz.data();
    job_.d_t = grads->t.data();
    job_.d_log_scales = grads->log_scales.data();
    job_.d_rot_left = grads->rot_left.data();
    job_.d_rot_right = grads->rot_right.data();
    job_.d_opacity_logit = grads->opacity_logit.data();
  }

  void Chunk(std::int64_t b, std::int64_t e) const {
    thread_local ColourRowBlock block;
    if (rows_done_) block.Fit(model_.channels, model_.rest_stride());
    for (std::int64_t first = b; first < e; first += kRowsDoneBlock)
      Block(first, std::min(first + kRowsDoneBlock, e), &block);
  }

 private:
  // Rows [first, last). Only the Gaussians the forward kept get a gradient. The kernel runs on
  // them alone, packed into full batches (in a dynamic scene most Gaussians are culled by time);
  // the others' rows are zero, as the kernel would have written them.
  void Block(std::int64_t first, std::int64_t last, ColourRowBlock* block) const {
    const int channels = model_.channels;
    const bool to_block = static_cast<bool>(rows_done_);
    // The full buffers are written whole; the block up to its `written` coefficients.
    int coefficients = model_.basis.coefficients();
    if (to_block) {
      block->written = std::max(block->written, job_.used_coefficients);
      coefficients = block->written;
    }
    const std::size_t rest_floats = static_cast<std::size_t>(coefficients - 1) * channels;
    const std::size_t stride = model_.rest_stride();
    GaussianGradients* grads = grads_;
    const auto colour_rows = [&](std::size_t i) {
      const std::size_t row = to_block ? i - static_cast<std::size_t>(first) : i;
      return std::pair{to_block ? &block->dc[row * channels] : &grads->color_dc[i * channels],
                       to_block ? &block->rest[row * stride] : &grads->color_rest[i * stride]};
    };
    std::int64_t kept[kRowsDoneBlock];
    int num_kept = 0;
    for (std::int64_t g = first; g < last; ++g) {
      const std::size_t i = static_cast<std::size_t>(g);
      if (state_.splats.radius[i] > 0) {
        kept[num_kept++] = g;
        continue;
      }
      ZeroGeometryGradients(i, grads);
      if (to_block) {
        char& zero = block->row_is_zero[static_cast<std::size_t>(g - first)];
        if (zero) continue;
        zero = 1;
      }
      const auto [gdc, grest] = colour_rows(i);
      std::fill_n(gdc, channels, 0.0f);
      std::fill_n(grest, rest_floats, 0.0f);
    }
    alignas(64) float batch_w[kMaxColorCoefficients * kPreprocessBatch];
    // The kernel gives the used coefficients' weights; the rest of the row is written as zeros.
    float w[kMaxColorCoefficients];
    std::fill(w + job_.used_coefficients, w + coefficients, 0.0f);
    for (int k = 0; k < num_kept; k += kPreprocessBatch) {
      const int count = std::min(kPreprocessBatch, num_kept - k);
      PreprocessBackwardSimd(job_, kept + k, count, batch_w);
      for (int l = 0; l < count; ++l) {
        const std::size_t i = static_cast<std::size_t>(kept[k + l]);
        const auto [gdc, grest] = colour_rows(i);
        if (to_block) block->row_is_zero[i - static_cast<std::size_t>(first)] = 0;
        LaneWeights(batch_w, l, job_.used_coefficients, w);
        WriteColourGradient(model_, i, w, options_, state_, coefficients, gdc, grest);
      }
    }
    if (to_block) rows_done_(first, last, GradientRows{block->dc.data(), block->rest.data()});
  }

  const GaussianModel& model_;
  const RenderOptions& options_;
  const FrameState& state_;
  GaussianGradients* grads_;
  const GradientRowsDone& rows_done_;
  PreprocessSimdJob job_;
};

}  // namespace

void PreprocessBackwardFast(const GaussianModel& model,
                            const ViewParams<float>& view,
                            float time,
                            const RenderOptions& options,
                            const FrameState& state,
                            GaussianGradients* grads,
                            const GradientRowsDone& rows_done) {
  const std::size_t n = model.size();
  // With rows_done the colour rows go only to it, so `grads` may lack colour buffers.
  HDR4D_CHECK(grads->size() == n &&
              (rows_done || (grads->color_rest.size() == model.color_rest.size() &&
                             grads->color_dc.size() == model.color_dc.size())));
  HDR4D_CHECK(state.splat_grads.opacity.size() == n);
  const FastBackward backward(model, view, time, options, state, grads, rows_done);
  ParallelForChunks(static_cast<std::int64_t>(n), kGaussianGrain,
                    [&](std::int64_t b, std::int64_t e) { backward.Chunk(b, e); });
}

}  // namespace hdr4d::method
