// The engine of the Dynamic Tone Mapper, templated on the scalar so that finite-difference tests
// run the whole chain (window -> context learner -> f -> tone curves -> LDR) in double. The
// ToneMapper (dynamic_tone_mapper.h) wraps DtmCore<float> with the radiance bank, the parameter
// arrays and the checkpoint format.
//
// Parameters, one flat array: the context learner's, then the R, G and B curves' (each in
// ToneCurveShape's layout). Values are mapped in parallel over fixed chunks of colours; the
// parameter gradients of a chunk are gathered on their own and added in chunk order, so results
// are bit-identical at any thread count.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "method/tonemap/context_learner.h"
#include "method/tonemap/tone_curve.h"
#include "method/tonemap/tone_mapper.h"
#include "method/tonemap/tone_table_simd.h"

namespace hdr4d::method {

// Curve inputs x = log HDR + log exposure are clamped to +-kMaxCurveInput (zero gradient
// outside): a finite bound keeps every product in the network finite. |x| = 1e6 is a radiance
// of e^1e6, far beyond anything real.
inline constexpr double kMaxCurveInput = 1e6;
// Colours per parallel chunk.
inline constexpr std::int64_t kDtmChunk = 2048;

struct DtmShape {
  ContextLearnerShape context;
  ToneCurveShape curve;
  int window = 20;         // k
  int table_nodes = 1024;  // 0: the direct path only

  // From a valid configuration (checked).
  static DtmShape FromConfig(const ToneMapperConfig& config);
  std::size_t NumParams() const { return context.NumParams() + 3 * curve.NumParams(); }
  std::size_t CurveOffset(int channel) const {
    return context.NumParams() + std::size_t(channel) * curve.NumParams();
  }
};

template <typename T>
class DtmCore {
 public:
  explicit DtmCore(const DtmShape& shape);

  const DtmShape& shape() const { return shape_; }
  // PyTorch default initialisation of every part, from one seed.
  void Init(std::uint64_t seed, T* params) const;

  // Prepares one view: copies the parameters (the frame keeps them even if the caller's change),
  // runs the context learner on the window (length x 3, detached) and builds the tables. Drops
  // any gradient still pending from the previous view (callers flush it first).
  void BeginFrame(const T* params, const T* window, int length, T log_exposure);
  bool ready() const { return ready_; }
  // Forgets the frame (its parameters are stale): BeginFrame is needed before the next Map.
  void Invalidate();

  // The float tabulated path runs its per-value loop in SIMD (tone_table_simd.h) unless this is
  // switched off (tests compare both); other paths are scalar.
  void set_simd(bool on) { simd_ = on; }

  const std::vector<T>& context() const { return f_; }
  T log_exposure() const { return log_e_; }
  const FrameToneCurve<T>& curve(int channel) const { return curves_[channel]; }

  // n interleaved RGB colours; see ToneMapper::Map / MapBackward.
  void Map(const T* log_hdr, std::size_t n, T* ldr) const;
  void MapBackward(const T* log_hdr, std::size_t n, const T* dL_dldr, T* dL_dlog_hdr);

  // True after a MapBackward whose gradient EndFrameBackward has not flushed yet.
  bool has_pending_gradient() const { return pending_; }
  // ADDS the view's parameter gradient (curves and, through f, the context learner).
  void EndFrameBackward(T* dL_dparams);

 private:
  std::size_t DirectStride() const { return 3 * shape_.curve.NumParams() + shape_.context.size; }
  bool UseSimd() const;
  detail::ToneTableView TableView() const;
  // One value of channel c on the scalar path.
  T MapValue(T log_hdr, int c, std::vector<T>* scratch) const;
  // The direct path's backward of one value: adds to the chunk's direct gradients `dacc`
  // (zeroed on first use, flagged in *dacc_used); returns dL/dlog_hdr.
  T DirectValueBackward(
      T log_hdr, T g, int c, std::vector<T>* scratch, T* dacc, char* dacc_used) const;
  void ResetAccumulators();
  // One chunk's share of MapBackward's gradient: its table nodes (3 x nodes), their zeroed,
  // touched range per channel (lo, hi), its direct path's gradients (DirectStride(), zeroed on
  // first use) and whether they were used.
  struct ChunkGradient {
    double* nodes;
    int* range;
    T* direct;
    char* direct_used;
  };
  // MapBackward's scalar path over values [v0, v0 + count).
  void ScalarChunkBackward(const T* log_hdr,
                           const T* dL_dldr,
                           T* dL_dlog_hdr,
                           std::size_t v0,
                           std::size_t count,
                           const ChunkGradient& acc) const;
  // Adds the chunks' gradients to the frame's, in chunk order.
  void AddChunkGradients(std::int64_t chunks);

  DtmShape shape_;
  bool tabulated_;
  int nodes_;
  bool simd_ = true;
  // The frame.
  bool ready_ = false;
  std::vector<T> context_params_, curve_params_, window_, f_;  // curve_params_: stored R, G, B
  ContextTape<T> tape_;
  T log_e_ = T(0);
  std::array<FrameToneCurve<T>, 3> curves_;
  std::vector<float> table_z_, table_dz_;  // the three tables concatenated (float SIMD path)
  // The frame's gradient: dL/dz per table node (3 x nodes) and the direct path's curve
  // parameter gradients then dL/df (DirectStride()).
  bool pending_ = false, direct_used_ = false;
  std::vector<double> node_grad_, direct_grad_;
  // Per-chunk partial sums of MapBackward (reused across calls).
  std::vector<double> chunk_nodes_;  // chunks x 3 x nodes
  std::vector<int> chunk_range_;     // chunks x 3 x (lo, hi): the zeroed, touched node range
  std::vector<T> chunk_direct_;      // chunks x DirectStride()
  std::vector<char> chunk_direct_used_;
};

extern template class DtmCore<float>;
extern template class DtmCore<double>;

}  // namespace hdr4d::method
