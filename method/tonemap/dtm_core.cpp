#include "method/tonemap/dtm_core.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <type_traits>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/tonemap/monotone_mlp.h"
#include "method/tonemap/tone_table_simd.h"

namespace hdr4d::method {
namespace {

// Independent seeds for the parts from one user seed (SplitMix64 finaliser).
std::uint64_t SubSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// x = log HDR + log exposure, clamped; *inside is false where the clamp cut (zero gradient).
template <typename T>
T CurveInput(T log_hdr, T log_e, bool* inside) {
  const T x = log_hdr + log_e;
  const T lim = T(kMaxCurveInput);
  *inside = !(x < -lim || x > lim);
  return x < -lim ? -lim : (x > lim ? lim : x);
}

}  // namespace

DtmShape DtmShape::FromConfig(const ToneMapperConfig& config) {
  HDR4D_CHECK(config.Validate().empty());
  DtmShape s;
  s.context.kind = *ParseContextKind(config.context_learner);
  s.context.size = config.context_size;
  s.curve.context_size = config.context_size;
  s.curve.hidden = config.curve_hidden;
  s.curve.monotone = config.monotone_curves;
  s.window = config.context_window;
  s.table_nodes = config.tabulated ? config.table_nodes : 0;
  return s;
}

template <typename T>
DtmCore<T>::DtmCore(const DtmShape& shape)
    : shape_(shape), tabulated_(shape.table_nodes >= 2), nodes_(shape.table_nodes) {
  HDR4D_CHECK(shape.table_nodes == 0 || shape.table_nodes >= 2);
  HDR4D_CHECK(shape.context.size == shape.curve.context_size && shape.window >= 1);
  node_grad_.assign(tabulated_ ? 3 * std::size_t(nodes_) : 0, 0.0);
  direct_grad_.assign(DirectStride(), 0.0);
}

template <typename T>
void DtmCore<T>::Init(std::uint64_t seed, T* params) const {
  ContextLearnerInit(shape_.context, SubSeed(seed, 0), params);
  for (int c = 0; c < 3; ++c) {
    MlpInit(shape_.curve.Mlp(), SubSeed(seed, 1 + c), params + shape_.CurveOffset(c));
  }
}

template <typename T>
void DtmCore<T>::ResetAccumulators() {
  std::fill(node_grad_.begin(), node_grad_.end(), 0.0);
  std::fill(direct_grad_.begin(), direct_grad_.end(), 0.0);
  pending_ = direct_used_ = false;
}

template <typename T>
void DtmCore<T>::Invalidate() {
  ready_ = false;
  ResetAccumulators();
}

template <typename T>
void DtmCore<T>::BeginFrame(const T* params, const T* window, int length, T log_exposure) {
  HDR4D_CHECK(length >= 1 && length <= std::max(shape_.window, 1));
  ResetAccumulators();
  const std::size_t nc = shape_.context.NumParams();
  context_params_.assign(params, params + nc);
  curve_params_.assign(params + nc, params + shape_.NumParams());
  window_.assign(window, window + std::size_t(length) * ContextLearnerShape::kInputs);
  f_.resize(shape_.context.size);
  ContextLearnerForward(shape_.context, context_params_.data(), window_.data(), length, f_.data(),
                        &tape_);
  log_e_ = log_exposure;
  // The three tables are independent: build them in parallel.
  ParallelForChunks(3, 1, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t c = b; c < e; ++c) {
      curves_[c].Prepare(shape_.curve, params + shape_.CurveOffset(int(c)), f_.data(),
                         tabulated_ ? nodes_ : 0);
    }
  });
  if (UseSimd()) {
    table_z_.resize(3 * std::size_t(nodes_));
    table_dz_.resize(3 * std::size_t(nodes_));
    for (int c = 0; c < 3; ++c) {
      const std::vector<T>& z = curves_[c].node_values();
      for (int j = 0; j < nodes_; ++j) {
        table_z_[c * nodes_ + j] = float(z[j]);
        table_dz_[c * nodes_ + j] = j + 1 < nodes_ ? float(z[j + 1] - z[j]) : 0.0f;
      }
    }
  }
  ready_ = true;
}

namespace {

// Per-chunk buffers of the SIMD path, kept per thread (no allocation after the first chunk).
struct SimdScratch {
  std::vector<std::int32_t> node, outside;
  std::vector<float> a0, a1;
  void Reserve(std::size_t n) {
    if (node.size() < n) {
      node.resize(n);
      outside.resize(n);
      a0.resize(n);
      a1.resize(n);
    }
  }
};
thread_local SimdScratch tls_simd;

}  // namespace

template <typename T>
detail::ToneTableView DtmCore<T>::TableView() const {
  detail::ToneTableView view;
  view.z = table_z_.data();
  view.dz = table_dz_.data();
  view.nodes = nodes_;
  view.x_min = float(kTableXMin);
  view.x_max = float(kTableXMax);
  view.inv_step = float(1.0 / ((kTableXMax - kTableXMin) / (nodes_ - 1)));
  view.log_exposure = float(log_e_);
  return view;
}

template <typename T>
bool DtmCore<T>::UseSimd() const {
  return std::is_same_v<T, float> && simd_ && tabulated_;
}

template <typename T>
T DtmCore<T>::MapValue(T log_hdr, int c, std::vector<T>* scratch) const {
  const FrameToneCurve<T>& curve = curves_[c];
  bool inside;
  const T x = CurveInput(log_hdr, log_e_, &inside);
  if (std::isnan(x)) return x;  // a NaN colour stays visible downstream
  if (tabulated_ && curve.InTable(x)) {
    int j;
    T w;
    curve.Locate(x, &j, &w);
    return StableSigmoid(curve.TablePreSigmoid(j, w));
  }
  if (scratch->empty()) scratch->resize(curve.DirectScratchSize());
  return curve.Direct(x, scratch->data());
}

template <typename T>
T DtmCore<T>::DirectValueBackward(
    T log_hdr, T g, int c, std::vector<T>* scratch, T* dacc, char* dacc_used) const {
  const FrameToneCurve<T>& curve = curves_[c];
  bool inside;
  const T x = CurveInput(log_hdr, log_e_, &inside);
  if (std::isnan(x)) return x;  // adds nothing to the shared parameters' gradients
  if (g == T(0)) return T(0);
  if (scratch->empty()) scratch->resize(curve.DirectScratchSize());
  if (!*dacc_used) {
    std::fill(dacc, dacc + DirectStride(), T(0));
    *dacc_used = 1;
  }
  const std::size_t curve_params = shape_.curve.NumParams();
  curve.Direct(x, scratch->data());
  const T dx =
      curve.DirectBackward(g, scratch->data(), dacc + c * curve_params, dacc + 3 * curve_params);
  return inside ? dx : T(0);
}

template <typename T>
void DtmCore<T>::Map(const T* log_hdr, std::size_t n, T* ldr) const {
  HDR4D_CHECK(ready_);
  ParallelForChunks(std::int64_t(n), kDtmChunk, [&](std::int64_t b, std::int64_t e) {
    std::vector<T> scratch;  // direct path only, allocated on its first value
    const std::size_t v0 = std::size_t(b) * 3, count = std::size_t(e - b) * 3;
    if constexpr (std::is_same_v<T, float>) {
      if (UseSimd()) {
        tls_simd.Reserve(count);
        const std::size_t n_out = detail::ToneTableForward(TableView(), log_hdr + v0, count,
                                                             ldr + v0, tls_simd.outside.data());
        for (std::size_t k = 0; k < n_out; ++k) {
          const std::size_t v = v0 + tls_simd.outside[k];
          ldr[v] = MapValue(log_hdr[v], int(v % 3), &scratch);
        }
        return;
      }
    }
    for (std::size_t v = v0; v < v0 + count; ++v) {
      ldr[v] = MapValue(log_hdr[v], int(v % 3), &scratch);
    }
  });
}

namespace {

// Grows a chunk's zeroed node range [lo, hi] of one channel (lo > hi: empty; `a` that channel's
// nodes) to cover nodes j and j + 1, zeroing the nodes it adds.
inline void CoverNodes(int j, double* a, int& lo, int& hi) {
  if (lo > hi) {
    lo = j;
    hi = j + 1;
    a[j] = a[j + 1] = 0.0;
    return;
  }
  if (j < lo) {
    std::fill(a + j, a + lo, 0.0);
    lo = j;
  }
  if (j + 1 > hi) {
    std::fill(a + hi + 1, a + j + 2, 0.0);
    hi = j + 1;
  }
}

// The SIMD path's table backward of one chunk's `count` values: ToneTableBackward's node and
// weights per value, each channel's touched node range (indices into the concatenated tables)
// zeroed in `acc` and recorded in `range`, then the scatter in value order. Returns how many
// values lie outside the tables (their indices in tls_simd.outside), which it leaves alone.
std::size_t SimdChunkTableBackward(const detail::ToneTableView& view,
                                   const float* log_hdr,
                                   const float* dL_dldr,
                                   std::size_t count,
                                   float* dL_dlog_hdr,
                                   double* acc,
                                   int* range) {
  SimdScratch& s = tls_simd;
  s.Reserve(count);
  const std::size_t n_out =
      detail::ToneTableBackward(view, log_hdr, dL_dldr, count, dL_dlog_hdr, s.node.data(),
                                s.a0.data(), s.a1.data(), s.outside.data());
  std::int32_t lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {-1, -1, -1};
  for (std::size_t v = 0; v < count; v += 3) {
    for (int c = 0; c < 3; ++c) {
      if (s.a0[v + c] != 0.0f || s.a1[v + c] != 0.0f) {
        lo[c] = std::min(lo[c], s.node[v + c]);
        hi[c] = std::max(hi[c], s.node[v + c] + 1);
      }
    }
  }
  for (int c = 0; c < 3; ++c) {
    if (hi[c] < 0) continue;
    std::fill(acc + lo[c], acc + hi[c] + 1, 0.0);
    range[2 * c] = lo[c] - c * view.nodes;
    range[2 * c + 1] = hi[c] - c * view.nodes;
  }
  for (std::size_t v = 0; v < count; ++v) {
    if (s.a0[v] != 0.0f || s.a1[v] != 0.0f) {
      acc[s.node[v]] += double(s.a0[v]);
      acc[s.node[v] + 1] += double(s.a1[v]);
    }
  }
  return n_out;
}

}  // namespace

template <typename T>
void DtmCore<T>::MapBackward(const T* log_hdr, std::size_t n, const T* dL_dldr, T* dL_dlog_hdr) {
  HDR4D_CHECK(ready_);
  const std::int64_t chunks = (std::int64_t(n) + kDtmChunk - 1) / kDtmChunk;
  const std::size_t node_stride = tabulated_ ? 3 * std::size_t(nodes_) : 0;
  const std::size_t direct_stride = DirectStride();
  if (chunk_nodes_.size() < chunks * node_stride) chunk_nodes_.resize(chunks * node_stride);
  if (chunk_direct_.size() < chunks * direct_stride) chunk_direct_.resize(chunks * direct_stride);
  chunk_range_.assign(chunks * 6, 0);
  chunk_direct_used_.assign(chunks, 0);
  ParallelForChunks(std::int64_t(n), kDtmChunk, [&](std::int64_t b, std::int64_t e) {
    const std::int64_t chunk = b / kDtmChunk;
    ChunkGradient acc{chunk_nodes_.data() + chunk * node_stride, chunk_range_.data() + chunk * 6,
                      chunk_direct_.data() + chunk * direct_stride, &chunk_direct_used_[chunk]};
    for (int c = 0; c < 3; ++c) {
      acc.range[2 * c] = 1;  // empty: lo > hi
      acc.range[2 * c + 1] = 0;
    }
    const std::size_t v0 = std::size_t(b) * 3, count = std::size_t(e - b) * 3;
    if constexpr (std::is_same_v<T, float>) {
      if (UseSimd()) {
        const std::size_t n_out =
            SimdChunkTableBackward(TableView(), log_hdr + v0, dL_dldr + v0, count,
                                   dL_dlog_hdr ? dL_dlog_hdr + v0 : nullptr, acc.nodes, acc.range);
        std::vector<T> scratch;
        for (std::size_t k = 0; k < n_out; ++k) {
          const std::size_t v = v0 + tls_simd.outside[k];
          const T dx = DirectValueBackward(log_hdr[v], dL_dldr[v], int(v % 3), &scratch,
                                           acc.direct, acc.direct_used);
          if (dL_dlog_hdr) dL_dlog_hdr[v] = dx;
        }
        return;
      }
    }
    ScalarChunkBackward(log_hdr, dL_dldr, dL_dlog_hdr, v0, count, acc);
  });
  AddChunkGradients(chunks);
  pending_ = true;
}

template <typename T>
void DtmCore<T>::ScalarChunkBackward(const T* log_hdr,
                                     const T* dL_dldr,
                                     T* dL_dlog_hdr,
                                     std::size_t v0,
                                     std::size_t count,
                                     const ChunkGradient& acc) const {
  std::vector<T> scratch;
  for (std::size_t v = v0; v < v0 + count; ++v) {
    const int c = int(v % 3);
    const T g = dL_dldr[v];
    T dx = T(0);
    const FrameToneCurve<T>& curve = curves_[c];
    bool inside;
    const T x = CurveInput(log_hdr[v], log_e_, &inside);
    if (g != T(0) && tabulated_ && curve.InTable(x)) {
      int j;
      T w;
      curve.Locate(x, &j, &w);
      const T y = StableSigmoid(curve.TablePreSigmoid(j, w));
      const T dz = g * y * (T(1) - y);
      dx = dz * curve.TableSlope(j);
      double* a = acc.nodes + std::size_t(c) * nodes_;
      CoverNodes(j, a, acc.range[2 * c], acc.range[2 * c + 1]);
      a[j] += double(dz) * double(T(1) - w);
      a[j + 1] += double(dz) * double(w);
    } else if (!(tabulated_ && curve.InTable(x))) {
      dx = DirectValueBackward(log_hdr[v], g, c, &scratch, acc.direct, acc.direct_used);
    }
    if (dL_dlog_hdr) dL_dlog_hdr[v] = dx;
  }
}

template <typename T>
void DtmCore<T>::AddChunkGradients(std::int64_t chunks) {
  const std::size_t node_stride = tabulated_ ? 3 * std::size_t(nodes_) : 0;
  const std::size_t direct_stride = DirectStride();
  // Chunk order: the same sums at any thread count.
  for (std::int64_t chunk = 0; chunk < chunks; ++chunk) {
    const double* acc = chunk_nodes_.data() + chunk * node_stride;
    const int* range = chunk_range_.data() + chunk * 6;
    for (int c = 0; c < 3 && tabulated_; ++c) {
      double* dst = node_grad_.data() + std::size_t(c) * nodes_;
      const double* src = acc + std::size_t(c) * nodes_;
      for (int j = range[2 * c]; j <= range[2 * c + 1]; ++j) dst[j] += src[j];
    }
    if (chunk_direct_used_[chunk]) {
      const T* src = chunk_direct_.data() + chunk * direct_stride;
      for (std::size_t k = 0; k < direct_stride; ++k) direct_grad_[k] += double(src[k]);
      direct_used_ = true;
    }
  }
}

template <typename T>
void DtmCore<T>::EndFrameBackward(T* dL_dparams) {
  if (!pending_) return;
  HDR4D_CHECK(ready_);
  const int d = shape_.context.size;
  const std::size_t curve_params = shape_.curve.NumParams();
  std::vector<T> df(d, T(0));
  // The curves' gradients are with respect to their effective parameters; with monotone curves
  // they go through |p| to the stored ones (monotone_mlp.h).
  const bool monotone = shape_.curve.monotone;
  const MlpShape mlp = shape_.curve.Mlp();
  std::vector<T> effective_grad(monotone ? curve_params : 0);
  for (int c = 0; c < 3 && tabulated_; ++c) {
    const double* g = node_grad_.data() + std::size_t(c) * nodes_;
    if (std::any_of(g, g + nodes_, [](double v) { return v != 0.0; })) {
      T* dst = dL_dparams + shape_.CurveOffset(c);
      if (!monotone) {
        curves_[c].TableBackward(g, dst, df.data());
        continue;
      }
      std::fill(effective_grad.begin(), effective_grad.end(), T(0));
      curves_[c].TableBackward(g, effective_grad.data(), df.data());
      MonotoneGradientAdd(mlp, curve_params_.data() + c * curve_params, effective_grad.data(),
                          dst);
    }
  }
  if (direct_used_) {
    for (int c = 0; c < 3; ++c) {
      T* dst = dL_dparams + shape_.CurveOffset(c);
      const double* src = direct_grad_.data() + c * curve_params;
      if (monotone) {
        MonotoneGradientAdd(mlp, curve_params_.data() + c * curve_params, src, dst);
      } else {
        for (std::size_t k = 0; k < curve_params; ++k) dst[k] += T(src[k]);
      }
    }
    for (int k = 0; k < d; ++k) df[k] += T(direct_grad_[3 * curve_params + k]);
  }
  ContextLearnerBackward(shape_.context, context_params_.data(), window_.data(), tape_, df.data(),
                         dL_dparams);
  ResetAccumulators();
}

template class DtmCore<float>;
template class DtmCore<double>;

}  // namespace hdr4d::method
