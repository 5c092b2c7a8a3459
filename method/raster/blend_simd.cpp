// The fast blend kernels (blend.h, backend kSimd): one 16x16 tile at a time, its pixels as
// Highway float vectors of at most 16 lanes (so a vector never straddles two tile rows; AVX-512
// takes a whole row). Compiled for every x86 target Highway 1.0.3 builds here (scalar, SSSE3,
// SSE4, AVX2, AVX-512) and chosen at run time with HWY_DYNAMIC_DISPATCH.
//
// Per frame, every listed Gaussian's kernel record (conic terms, opacity and its log2, reach
// extents, features) is packed once (PackSplats); per tile the records of its
// list are copied into a contiguous array and their reach box is turned into tile rows/columns.
// The reach box bounds the pixels where alpha can reach kMinAlpha; it only prunes work, the
// per-lane tests of the 3DGS rules still decide, so pruning never changes a result.
//
// The forward gathers each tile's records into the state (after the per-Gaussian records), so
// the backward of the same frame reads them contiguously instead of gathering again (a render,
// which no backward follows, reads the per-Gaussian records in place); while building its row
// lists the forward also drops, per row, the Gaussians whose power cannot reach the log
// threshold within the tile's columns (exact maximum on the row, with a rounding margin) and
// narrows the stored rows to those, which the backward then walks.
// Forward: pixel vectors go in pairs (a vector and the one below it: two independent T chains,
// the T -> test_T -> T recurrence being latency-bound), each pair walking only the Gaussians whose
// reach box covers its two rows (selected with Compress), T, colour and n_contrib (when a
// backward follows) in registers,
// and stopping when all its pixels are done.
// Backward: for each Gaussian back to front, the pixel vectors of its reach box that still list
// it (n_contrib per vector bounds the loop), each vector a block of 4x4 pixels (4x2 with 8
// lanes), with T and the "behind" colour (one value per pixel: its dot product with dL/dimage)
// in L1-resident planes and the Gaussian's gradient summed across the tile in registers; one
// horizontal reduction per Gaussian and tile (a shared transpose network with AVX-512) goes to
// its entry slot.
//
// The channel count is a template parameter for 1, 3, 4 and 6 channels (accumulators in
// registers) and a run-time value otherwise (accumulators in L1).
//
// Timings: benchmark/runtime/raster_benchmark, recorded in BENCHMARKS.md (history: docs/history/).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "method/raster/blend_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
// Must come after foreach_target.h.
#include <hwy/aligned_allocator.h>
#include <hwy/highway.h>
// Must come after highway.h.
#include <hwy/contrib/math/math-inl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "method/raster/blend.h"

HWY_BEFORE_NAMESPACE();
namespace hdr4d::method::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<float, kTileSize>;
using DI = hn::RebindToSigned<D>;
using V = hn::Vec<D>;
using VI = hn::Vec<DI>;
using M = hn::Mask<D>;

constexpr int kTilePixels = kTileSize * kTileSize;

// Record of one Gaussian gathered per tile (array of structures, read by broadcasts).
constexpr int kRecMeanX = 0;
constexpr int kRecMeanY = 1;
// The exponent terms are in log2 units (times log2(e)), so the kernels take exp2 of the power
// directly: two operations fewer per Gaussian and pixel vector.
constexpr int kRecHalfNegA = 2;  // -a / 2 log2(e)
constexpr int kRecNegB = 3;      // -b log2(e)
constexpr int kRecHalfNegC = 4;  // -c / 2 log2(e)
constexpr int kRecOpacity = 5;
// log2(opacity) (-inf where opacity <= 0 or NaN): the kernels take alpha = 2^(power + log2 o),
// the sum in the power's last multiply-add, so no multiply by the opacity per pixel vector.
constexpr int kRecLog2Opacity = 6;
constexpr int kRecFeatures = kRecordScalars;
static_assert(kRecLog2Opacity + 1 == kRecFeatures);
// A lane whose power + log2 o is below this has alpha < kMinAlpha (2^-125.5 <= it, so the
// unclamped exp2 is valid above it); the margin (1.5e-4, about the reach boxes' 1e-4 of a natural
// log) covers the roundings. It only prunes: alpha >= kMinAlpha decides.
constexpr float kLogAlphaFloor = -7.994353f - 1.5e-4f;  // log2(1/255) - margin
static_assert(kMinAlpha == 1.0f / 255.0f);
// After the features: the reach box. In the per-Gaussian records, 4 floats: the first and last
// pixel row and column (absolute, inclusive) of pixel centres the Gaussian can reach. In the
// per-entry tile records, the tile rows and columns (0..15, inclusive; row0 > row1 when it
// reaches none) as 4 bytes, each value + 1, in one slot (tile_records are the biggest per-entry
// buffer: 4 bytes instead of 16). The backward's natural -a and -c are read from the splats'
// conic instead of stored.
constexpr int kBoxRow0 = 0;
constexpr int kBoxRow1 = 1;
constexpr int kBoxCol0 = 2;
constexpr int kBoxCol1 = 3;
HWY_INLINE int Box(const float* r, int channels, int k) {
  return reinterpret_cast<const unsigned char*>(r + kRecFeatures + channels)[k] - 1;
}
HWY_INLINE void SetBox(float* r, int channels, int k, int value) {
  reinterpret_cast<unsigned char*>(r + kRecFeatures + channels)[k] =
      static_cast<unsigned char>(value + 1);
}

// Pixel centre offsets within a tile, in vector order (row-major).
struct PixelOffsets {
  alignas(64) float x[kTilePixels];
  alignas(64) float y[kTilePixels];
  constexpr PixelOffsets() : x(), y() {
    for (int p = 0; p < kTilePixels; ++p) {
      x[p] = static_cast<float>(p % kTileSize) + 0.5f;
      y[p] = static_cast<float>(p / kTileSize) + 0.5f;
    }
  }
};
constexpr PixelOffsets kOffsets;

// Aligned per-thread working memory that only grows.
template <typename T>
class Scratch {
 public:
  T* Get(std::size_t n) {
    if (n > capacity_) {
      capacity_ = std::max(n, 2 * capacity_);
      data_ = hwy::AllocateAligned<T>(capacity_);
    }
    return data_.get();
  }

 private:
  hwy::AlignedFreeUniquePtr<T[]> data_;
  std::size_t capacity_ = 0;
};

// 2^n for a whole float n in [-126, 127] (garbage outside): n + 1.5 * 2^23 + 127 is exact and
// holds n + 127 in its low mantissa bits, which the shift moves into the exponent field (the bits
// above fall off). One add and one shift; Highway's float-to-int conversion is five
// instructions here (it fixes up overflow), and these sit in the blend kernels' inner loops.
HWY_INLINE V Pow2Whole(D d, V n) {
  const DI di;
  const V biased = hn::Add(n, hn::Set(d, 12582912.0f + 127.0f));
  return hn::BitCast(d, hn::ShiftLeft<23>(hn::BitCast(di, biased)));
}

constexpr float kLog2E = 1.44269504088896341f;
constexpr float kLn2 = 0.693147180559945309f;

// 2^x for x in [-125.5, 0] without the clamp: outside that range the result is garbage (maybe inf
// or NaN), so only for callers that mask such lanes out of every result (the blend kernels).
// x = n + r, |r| <= 1/2 exact, 2^r by a degree-5 minimax polynomial (coefficients from a Remez
// fit of the relative error, 7.5e-8; 2.1e-7 with float coefficients and float Horner steps, as
// a degree-6 Taylor polynomial gives with one step more), 2^n in the exponent bits (with
// AVX-512 one vscalefps: the add, shift and multiply in one instruction).
HWY_INLINE V FastExp2UnclampedV(D d, V x) {
  const V n = hn::Round(x);
  const V r = hn::Sub(x, n);
  V p = hn::Set(d, 0.0013276472454890609f);
  p = hn::MulAdd(p, r, hn::Set(d, 0.009675540961325169f));
  p = hn::MulAdd(p, r, hn::Set(d, 0.05550713092088699f));
  p = hn::MulAdd(p, r, hn::Set(d, 0.24022120237350464f));
  p = hn::MulAdd(p, r, hn::Set(d, 0.6931469440460205f));
  p = hn::MulAdd(p, r, hn::Set(d, 1.0f));
#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
  static_assert(hn::MaxLanes(D()) == 16);
  return V{_mm512_scalef_ps(p.raw, n.raw)};
#else
  return hn::Mul(p, Pow2Whole(d, n));
#endif
}

// 2^x clamped to [-125.5, 0] (exp of [-87, 0]).
HWY_INLINE V FastExp2V(D d, V x) {
  return FastExp2UnclampedV(d, hn::Min(hn::Max(x, hn::Set(d, -125.5f)), hn::Zero(d)));
}

#if HWY_TARGET == HWY_AVX2
// Highway 1.0.3's Compress of 32-bit lanes on AVX2 builds its 1 KB index table on the stack at
// every call (a function-local constexpr array, copied by rep movsq: 15% of the AVX2 forward's
// samples on a 200x200 run). The same permutation from a table built once: per mask of 8 bits,
// the selected lanes' indices as 4-bit fields, lowest first.
struct CompressIndexTable {
  std::uint32_t packed[256] = {};
  constexpr CompressIndexTable() {
    for (int bits = 0; bits < 256; ++bits) {
      std::uint32_t p = 0;
      int n = 0;
      for (int i = 0; i < 8; ++i) {
        if ((bits >> i) & 1) p |= static_cast<std::uint32_t>(i) << (4 * n++);
      }
      packed[bits] = p;
    }
  }
};
constexpr CompressIndexTable kCompressIndexTable;
#endif

// Stores a full vector at `out` whose first CountTrue(m) lanes are the lanes of `ids` where m is
// set, in order (the rest is unspecified): Compress, without Highway's per-call table on AVX2.
template <class MI>
HWY_INLINE void StoreCompressed(VI ids, MI m, std::int32_t* out) {
  const DI di;
#if HWY_TARGET == HWY_AVX2
  const auto bits = static_cast<unsigned>(
      _mm256_movemask_ps(_mm256_castsi256_ps(hn::VecFromMask(di, m).raw)));
  const __m256i fields = _mm256_set1_epi32(static_cast<int>(kCompressIndexTable.packed[bits]));
  const __m256i index = _mm256_and_si256(
      _mm256_srlv_epi32(fields, _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28)),
      _mm256_set1_epi32(7));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out),
                      _mm256_permutevar8x32_epi32(ids.raw, index));
#else
  hn::StoreU(hn::Compress(ids, m), di, out);
#endif
}

// Packs the per-Gaussian part of the records of the listed Gaussians among ids [begin, end) into
// job.packed (stride PackedStride(channels)), once per frame, one vector of consecutive ids at a
// time: reads and writes stream (in depth order both were at random, and the record stores
// waited on their lines). The reach
// box bounds the ellipse power >= log threshold: for a positive definite conic Q, max |dy| over
// d^T Q d <= 2t is sqrt(2t a / det Q) (and sqrt(2t c / det Q) for dx), widened by 1e-4 relative
// + 1e-3 px + one ulp of the mean, far beyond the float error of `power`, of this float
// evaluation (det by the difference-of-products FMA trick, accurate to 2 ulp) and of the row
// arithmetic below; the exact per-lane tests still decide, and the log threshold itself only
// prunes (alpha >= kMinAlpha decides). In the packed form the row/column slots hold the box as
// absolute pixel indices (inclusive; empty when it reaches nothing, unbounded for a conic that is
// not positive definite), so that a tile only shifts and clamps them.
void PackSplats(const TileJob& job, std::int64_t begin, std::int64_t end) {
  const D d;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int channels = job.channels;
  const int stride = PackedStride(channels);
  const V inf = hn::Set(d, std::numeric_limits<float>::infinity());
  const V zero = hn::Zero(d);
  const V log2e = hn::Set(d, kLog2E);
  const V neg_half_log2e = hn::Set(d, -0.5f * kLog2E);
  const V bound = hn::Set(d, 8388608.0f);  // +-2^23: whole floats stay exact
  HWY_ALIGN std::int32_t ids[kTileSize];
  constexpr int kBox = kRecFeatures;  // the 4 box fields follow the scalars in `fields`
  HWY_ALIGN float fields[(kRecFeatures + 4) * kTileSize];
  for (std::int64_t i = begin; i < end; i += lanes) {
    const int n = static_cast<int>(std::min<std::int64_t>(lanes, end - i));
    for (int k = 0; k < lanes; ++k) ids[k] = static_cast<std::int32_t>(i + (k < n ? k : 0));
    const VI g = hn::Load(di, ids);
    const VI g2 = hn::Add(g, g);
    const VI g3 = hn::Add(g2, g);
    const V mx = hn::GatherIndex(d, job.mean2d, g2);
    const V my = hn::GatherIndex(d, job.mean2d + 1, g2);
    const V a = hn::GatherIndex(d, job.conic, g3);
    const V b = hn::GatherIndex(d, job.conic + 1, g3);
    const V c = hn::GatherIndex(d, job.conic + 2, g3);
    const V o = hn::GatherIndex(d, job.opacity, g);
    const M positive = hn::Gt(o, zero);
    const V log_t = hn::Sub(hn::Log(d, hn::Div(hn::Set(d, kMinAlpha), o)), hn::Set(d, 1e-4f));
    const V threshold = hn::IfThenElse(positive, log_t, inf);
    // det = a c - b b: w - b b is exact by FMA, so det rounds once more at most.
    const V w = hn::Mul(b, b);
    const V det = hn::Add(hn::MulSub(a, c, w), hn::NegMulAdd(b, b, w));
    const M pd = hn::And(hn::And(hn::Gt(a, zero), hn::Gt(c, zero)),
                         hn::And(hn::Gt(det, zero), hn::Lt(det, inf)));
    const V t2 = hn::Mul(hn::Set(d, -2.0f), threshold);
    const V cx = hn::Sub(mx, hn::Set(d, 0.5f));  // pixel index i has its centre at i + 0.5
    const V cy = hn::Sub(my, hn::Set(d, 0.5f));
    const V rel = hn::Set(d, 1.0f + 1e-4f);
    const V ulp = hn::Set(d, 1.2e-7f);
    const V ex =
        hn::MulAdd(hn::Abs(cx), ulp,
                   hn::MulAdd(hn::Sqrt(hn::Div(hn::Mul(t2, c), det)), rel, hn::Set(d, 1e-3f)));
    const V ey =
        hn::MulAdd(hn::Abs(cy), ulp,
                   hn::MulAdd(hn::Sqrt(hn::Div(hn::Mul(t2, a), det)), rel, hn::Set(d, 1e-3f)));
    // Reaches nothing (threshold > 0), everywhere (not positive definite) or the box.
    const M reaches = hn::Le(threshold, zero);
    const auto lo = [&](V centre, V extent) {
      const V box = hn::IfThenElse(pd, hn::Ceil(hn::Sub(centre, extent)), hn::Neg(inf));
      return hn::Min(hn::Max(hn::IfThenElse(reaches, box, inf), hn::Neg(bound)), bound);
    };
    const auto hi = [&](V centre, V extent) {
      const V box = hn::IfThenElse(pd, hn::Floor(hn::Add(centre, extent)), inf);
      return hn::Min(hn::Max(hn::IfThenElse(reaches, box, hn::Neg(inf)), hn::Neg(bound)), bound);
    };
    const auto put = [&](int field, V v) { hn::Store(v, d, fields + field * lanes); };
    put(kRecMeanX, mx);
    put(kRecMeanY, my);
    put(kRecHalfNegA, hn::Mul(neg_half_log2e, a));
    put(kRecNegB, hn::Mul(hn::Neg(b), log2e));
    put(kRecHalfNegC, hn::Mul(neg_half_log2e, c));
    put(kRecOpacity, o);
    put(kRecLog2Opacity, hn::IfThenElse(positive, hn::Mul(hn::Log(d, o), log2e), hn::Neg(inf)));
    put(kBox + kBoxRow0, lo(cy, ey));
    put(kBox + kBoxRow1, hi(cy, ey));
    put(kBox + kBoxCol0, lo(cx, ex));
    put(kBox + kBoxCol1, hi(cx, ex));
    for (int k = 0; k < n; ++k) {
      const std::size_t id = static_cast<std::size_t>(ids[k]);
      if (job.rects[4 * id + 2] == job.rects[4 * id]) continue;  // in no tile: never read
      float* r = job.packed + id * stride;
      for (int f = 0; f < kRecFeatures; ++f) r[f] = fields[f * lanes + k];
      const float* feat = job.features + id * channels;
      for (int ch = 0; ch < channels; ++ch) r[kRecFeatures + ch] = feat[ch];
      for (int f = 0; f < 4; ++f) r[kRecFeatures + channels + f] = fields[(kBox + f) * lanes + k];
    }
  }
}

// The tile rows and columns (0..15, inclusive; row0 > row1 when none) that a packed record's
// absolute reach box covers in the tile at (x0, y0), stored + 1 as 4 bytes (SetBox's form).
HWY_INLINE void TileBox(const float* box, float fx0, float fy0, unsigned char* out) {
  // The packed bounds are absolute pixel indices: shift to the tile and clamp (whole numbers
  // below 2^24, so exact). One-lane vector min/max: no branches (ternaries compile to some).
  const auto clamp = [](float v, float lo, float hi) {
    const hn::CappedTag<float, 1> d1;
    return static_cast<int>(
        hn::GetLane(hn::Min(hn::Max(hn::Set(d1, v), hn::Set(d1, lo)), hn::Set(d1, hi))));
  };
  const float last = static_cast<float>(kTileSize - 1);
  const float size = static_cast<float>(kTileSize);
  const int col0 = clamp(box[kBoxCol0] - fx0, 0.0f, size);
  const int col1 = clamp(box[kBoxCol1] - fx0, -1.0f, last);
  const int row0 = clamp(box[kBoxRow0] - fy0, 0.0f, size);
  // No column: nothing.
  const int row1 = col0 > col1 ? -1 : clamp(box[kBoxRow1] - fy0, -1.0f, last);
  out[kBoxRow0] = static_cast<unsigned char>(row0 + 1);
  out[kBoxRow1] = static_cast<unsigned char>(row1 + 1);
  out[kBoxCol0] = static_cast<unsigned char>(col0 + 1);
  out[kBoxCol1] = static_cast<unsigned char>(col1 + 1);
}

// The packed per-Gaussian record (stride PackedStride) of point_list entry `entry`.
HWY_INLINE const float* EntryRecord(const TileJob& job, int entry, int stride) {
  return job.packed + static_cast<std::size_t>(job.point_list[entry]) * stride;
}

// Walking a tile's entries j = 0.. reads records in Gaussian order while entries are in depth
// order, so the loads miss the cache: fetch entry j's record kRecordAhead entries early. On two
// cores half the records were packed by the other core, whose lines arrive in about 110 ns, not
// 25 (a pointer chase on the AVX-512 host): 20 ahead took 1.8% off a syn200_20k iteration
// against 8, 0.7% against 12, and 32 was 2% slower again (paired runs, 2026-12-06).
constexpr int kRecordAhead = 20;
HWY_INLINE void PrefetchRecordAhead(const TileJob& job, int start, int j, int count, int stride) {
  if (j + kRecordAhead >= count) return;
  const float* ahead = EntryRecord(job, start + j + kRecordAhead, stride);
  __builtin_prefetch(ahead);
  __builtin_prefetch(ahead + stride - 1);
}

// Copies the packed records of tile entries [start, start + count) into `rec` (tile records)
// and replaces the reach box with the tile rows and columns it covers.
template <int kC>
void GatherRecords(const TileJob& job, int tile, int start, int count, float* rec) {
  const int channels = kC > 0 ? kC : job.channels;
  const int in_stride = PackedStride(channels);
  const int out_stride = TileRecordStride(channels);
  const int copied = kRecFeatures + channels;  // the scalars and the features
  const int x0 = (tile % job.tiles_x) * kTileSize;
  const int y0 = (tile / job.tiles_x) * kTileSize;
  const float fx0 = static_cast<float>(x0);
  const float fy0 = static_cast<float>(y0);
  const D d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  for (int j = 0; j < count; ++j) {
    PrefetchRecordAhead(job, start, j, count, in_stride);
    float* r = rec + static_cast<std::size_t>(j) * out_stride;
    const float* src = EntryRecord(job, start + j, in_stride);
    if (copied >= lanes) {
      // Whole vectors, the last one overlapping the one before (never past the record).
      int k = 0;
      for (; k + lanes < copied; k += lanes) hn::StoreU(hn::LoadU(d, src + k), d, r + k);
      hn::StoreU(hn::LoadU(d, src + copied - lanes), d, r + copied - lanes);
    } else {
      for (int k = 0; k < copied; ++k) r[k] = src[k];
    }
    TileBox(src + copied, fx0, fy0, reinterpret_cast<unsigned char*>(r + copied));
  }
}

// power + log2 o, with power = -0.5 (a dx^2 + c dy^2) - b dx dy (times log2(e), from the
// record), as dx (-a/2 dx - b dy) + ((-c/2 dy) dy + log2 o).
HWY_INLINE V PowerPlusLog2Opacity(const float* r, V dx, V dy, V log2o) {
  const D d;
  const V q = hn::MulAdd(hn::Set(d, r[kRecHalfNegA]), dx, hn::Mul(hn::Set(d, r[kRecNegB]), dy));
  return hn::MulAdd(dx, q, hn::MulAdd(hn::Mul(hn::Set(d, r[kRecHalfNegC]), dy), dy, log2o));
}

// out[k] = sum of the lanes of acc[k], k < kCount, in a fixed order. With AVX-512, groups of 8
// accumulators share one transpose-and-add network (23 instructions per group instead of ~9 per
// accumulator with SumOfLanes): block shuffles halve 16 lanes to 8, then to 4 per 128-bit block,
// then 64-bit and 32-bit interleaves finish within blocks.
template <int kCount>
HWY_INLINE void ReduceLanes(const V* acc, float* out) {
  const D d;
#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
  static_assert(hn::MaxLanes(D()) == 16);
  for (int base = 0; base < kCount; base += 8) {
    __m512 v[8];
    for (int k = 0; k < 8; ++k) v[k] = base + k < kCount ? acc[base + k].raw : _mm512_setzero_ps();
    __m512 s[4], t[2];
    for (int k = 0; k < 4; ++k)  // blocks [a0+a2, a1+a3, b0+b2, b1+b3]
      s[k] = _mm512_add_ps(_mm512_shuffle_f32x4(v[2 * k], v[2 * k + 1], _MM_SHUFFLE(1, 0, 1, 0)),
                           _mm512_shuffle_f32x4(v[2 * k], v[2 * k + 1], _MM_SHUFFLE(3, 2, 3, 2)));
    for (int k = 0; k < 2; ++k)  // block i holds accumulator 4k + i (4 partials)
      t[k] = _mm512_add_ps(_mm512_shuffle_f32x4(s[2 * k], s[2 * k + 1], _MM_SHUFFLE(2, 0, 2, 0)),
                           _mm512_shuffle_f32x4(s[2 * k], s[2 * k + 1], _MM_SHUFFLE(3, 1, 3, 1)));
    const __m512d t0 = _mm512_castps_pd(t[0]);
    const __m512d t1 = _mm512_castps_pd(t[1]);
    // Per block [x0+x2, x1+x3, y0+y2, y1+y3] (x: accumulator i, y: accumulator 4 + i).
    const __m512 u = _mm512_add_ps(_mm512_castpd_ps(_mm512_unpacklo_pd(t0, t1)),
                                   _mm512_castpd_ps(_mm512_unpackhi_pd(t0, t1)));
    const __m512 w = _mm512_add_ps(u, _mm512_permute_ps(u, _MM_SHUFFLE(2, 3, 0, 1)));
    HWY_ALIGN float lanes[16];
    _mm512_store_ps(lanes, w);
    for (int i = 0; i < 4; ++i) {
      if (base + i < kCount) out[base + i] = lanes[4 * i];
      if (base + 4 + i < kCount) out[base + 4 + i] = lanes[4 * i + 2];
    }
  }
#else
  for (int k = 0; k < kCount; ++k) out[k] = hn::GetLane(hn::SumOfLanes(d, acc[k]));
#endif
}

#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
// Index tables of a 3-way interleave of vectors of n lanes (n = 16 floats or 8 doubles, indices
// as wide as the lanes): output vector k, lane e holds source (nk + e) % 3's lane (nk + e) / 3.
// first: lanes from sources 0 and 1 (a two-source permute index: lane + n for source 1); third:
// lanes from source 2, where third_mask is set.
template <typename Index, int kLanes>
struct Interleave3Tables {
  alignas(64) Index first[3][kLanes] = {};
  alignas(64) Index third[3][kLanes] = {};
  std::uint16_t third_mask[3] = {};
  constexpr Interleave3Tables() {
    for (int k = 0; k < 3; ++k) {
      for (int e = 0; e < kLanes; ++e) {
        const int element = kLanes * k + e;
        const int source = element % 3, lane = element / 3;
        first[k][e] = source == 1 ? lane + kLanes : lane;
        third[k][e] = lane;
        if (source == 2) third_mask[k] = static_cast<std::uint16_t>(third_mask[k] | (1u << e));
      }
    }
  }
};
constexpr Interleave3Tables<std::int32_t, 16> kInterleave3Floats;
constexpr Interleave3Tables<std::int64_t, 8> kInterleave3Doubles;

// out[3 i + c] = v[c] lane i: 48 floats (3 channels of 16 pixels) in pixel order.
HWY_INLINE void StoreInterleaved3(const __m512 v[3], float* out) {
  const auto& t = kInterleave3Floats;
  for (int k = 0; k < 3; ++k) {
    const __m512 ab = _mm512_permutex2var_ps(v[0], _mm512_load_si512(t.first[k]), v[1]);
    _mm512_storeu_ps(out + 16 * k, _mm512_mask_permutexvar_ps(ab, t.third_mask[k],
                                                              _mm512_load_si512(t.third[k]), v[2]));
  }
}

// out[6 i + c] = v[c] lane i: 96 floats (6 channels of 16 pixels) in pixel order. Channels are
// paired (0-1, 2-3, 4-5) into 64-bit pixel halves first, then those interleave 3 ways.
HWY_INLINE void StoreInterleaved6(const __m512 v[6], float* out) {
  alignas(64) static constexpr std::int32_t kPairLow[16] = {0, 16, 1, 17, 2, 18, 3, 19,
                                                            4, 20, 5, 21, 6, 22, 7, 23};
  alignas(64) static constexpr std::int32_t kPairHigh[16] = {8,  24, 9,  25, 10, 26, 11, 27,
                                                             12, 28, 13, 29, 14, 30, 15, 31};
  const __m512i low = _mm512_load_si512(kPairLow), high = _mm512_load_si512(kPairHigh);
  const auto& t = kInterleave3Doubles;
  for (int half = 0; half < 2; ++half) {
    const __m512i idx = half == 0 ? low : high;
    __m512d pairs[3];
    for (int q = 0; q < 3; ++q)
      pairs[q] = _mm512_castps_pd(_mm512_permutex2var_ps(v[2 * q], idx, v[2 * q + 1]));
    for (int k = 0; k < 3; ++k) {
      const __m512d ab = _mm512_permutex2var_pd(pairs[0], _mm512_load_si512(t.first[k]), pairs[1]);
      _mm512_storeu_pd(reinterpret_cast<double*>(out + 48 * half + 16 * k),
                       _mm512_mask_permutexvar_pd(ab, static_cast<__mmask8>(t.third_mask[k]),
                                                  _mm512_load_si512(t.third[k]), pairs[2]));
    }
  }
}
#endif

// Blend state of one pixel vector in the forward.
template <int kC>
struct PixelState {
  V T;
  VI last;  // n_contrib
  M done;
  V acc[kC > 0 ? kC : 1];
  float* acc_mem;  // the colour, for a run-time channel count
};

// One Gaussian (record r, list position j) blended into one pixel vector; the 3DGS rules.
// kTrack: keep n_contrib (only a backward reads it).
template <int kC, bool kTrack>
HWY_INLINE void BlendStep(const float* r, int j, int channels, V px, V py, PixelState<kC>& st) {
  const D d;
  [[maybe_unused]] const DI di;
  const V dx = hn::Sub(hn::Set(d, r[kRecMeanX]), px);
  const V dy = hn::Sub(hn::Set(d, r[kRecMeanY]), py);
  const V log2o = hn::Set(d, r[kRecLog2Opacity]);
  const V x = PowerPlusLog2Opacity(r, dx, dy, log2o);  // log2 of the unclamped alpha
  const M reach = hn::AndNot(st.done, hn::Ge(x, hn::Set(d, kLogAlphaFloor)));
  // Lanes with x below the floor never contribute: their alpha reaches only masks and an
  // IfThenElseZero, so the clamps can go. x <= log2 o is the 3DGS rule power <= 0.
  const V alpha = hn::Min(hn::Set(d, kMaxAlpha), FastExp2UnclampedV(d, x));
  const M active = hn::And(reach, hn::And(hn::Le(x, log2o), hn::Ge(alpha, hn::Set(d, kMinAlpha))));
  // T - alpha T: one fused operation (T (1 - alpha) took two), beside the weight alpha T.
  const V test_T = hn::NegMulAdd(alpha, st.T, st.T);
  const M stop = hn::And(active, hn::Lt(test_T, hn::Set(d, kMinTransmittance)));
  const M contrib = hn::AndNot(stop, active);
  const V w = hn::IfThenElseZero(contrib, hn::Mul(alpha, st.T));
  if constexpr (kC > 0) {
    for (int c = 0; c < kC; ++c)
      st.acc[c] = hn::MulAdd(w, hn::Set(d, r[kRecFeatures + c]), st.acc[c]);
  } else {
    const std::size_t lanes = hn::Lanes(d);
    for (int c = 0; c < channels; ++c) {
      float* a = st.acc_mem + c * lanes;
      hn::Store(hn::MulAdd(w, hn::Set(d, r[kRecFeatures + c]), hn::Load(d, a)), d, a);
    }
  }
  st.T = hn::IfThenElse(contrib, test_T, st.T);
  if constexpr (kTrack)
    st.last = hn::IfThenElse(hn::RebindMask(di, contrib), hn::Set(di, j + 1), st.last);
  st.done = hn::Or(st.done, stop);
}

// Forward of one tile. Pixel vectors are processed in pairs, a vector and the one below it,
// whose blend chains are independent (the T -> test_T -> T recurrence is latency-bound), each
// pair walking the list of Gaussians whose reach box covers its two rows.
// kKeep (job.tile_records set: a backward follows): the records are gathered into the state's
// per-entry array, their rows narrowed for the backward, and n_contrib kept. Otherwise (a render)
// the kernel reads the per-Gaussian records where they are, through a pointer per entry, with the
// tile box beside it: no copy of the records (14% of the forward's samples went to it) and no
// n_contrib.
// A kernel long on purpose: the blend is the hottest loop of a step (BM_RasterForward); its per-
// Gaussian steps are the HWY_INLINE helpers above, and its phases share the tile's scratch.
template <int kC, bool kKeep>
void ForwardTileImpl(const TileJob& job, int tile) {
  const D d;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int channels = kC > 0 ? kC : job.channels;
  const int stride = TileRecordStride(channels);
  const int x0 = (tile % job.tiles_x) * kTileSize;
  const int y0 = (tile / job.tiles_x) * kTileSize;
  const int start = job.tile_ranges[tile];
  const int count = job.tile_ranges[tile + 1] - start;
  const int vectors_per_row = kTileSize / lanes;

  thread_local Scratch<float> acc_scratch;  // run-time channel count only
  thread_local Scratch<std::int32_t> list_scratch;
  thread_local Scratch<std::int32_t> list_scratch2;
  thread_local Scratch<const float*> pointer_scratch;  // without kKeep
  thread_local Scratch<unsigned char> box_scratch;     // without kKeep
  // kKeep: into the state's per-entry records, so the backward can reuse them.
  float* rec = nullptr;
  const float** records = nullptr;
  unsigned char* boxes = nullptr;
  if constexpr (kKeep) {
    rec = job.tile_records + static_cast<std::size_t>(start) * stride;
    GatherRecords<kC>(job, tile, start, count, rec);
  } else {
    records = pointer_scratch.Get(static_cast<std::size_t>(count) + 1);
    boxes = box_scratch.Get(4 * static_cast<std::size_t>(count) + 4);
    const int in_stride = PackedStride(channels);
    const float fx0 = static_cast<float>(x0), fy0 = static_cast<float>(y0);
    for (int j = 0; j < count; ++j) {
      PrefetchRecordAhead(job, start, j, count, in_stride);
      const float* src = EntryRecord(job, start + j, in_stride);
      records[j] = src;
      TileBox(src + kRecFeatures + channels, fx0, fy0, boxes + 4 * j);
    }
  }
  // Record j (scalars, then features) and its tile box field k.
  const auto record = [&](int j) -> const float* {
    if constexpr (kKeep) return rec + static_cast<std::size_t>(j) * stride;
    return records[j];
  };
  const auto box = [&](int j, int k) -> int {
    if constexpr (kKeep) return Box(record(j), channels, k);
    return boxes[4 * j + k] - 1;
  };
  float* acc_mem =
      kC > 0 ? nullptr : acc_scratch.Get(2 * static_cast<std::size_t>(channels) * lanes);

  // Per pair of tile rows, the Gaussians (in depth order) whose reach box covers either row,
  // selected 1 vector of Gaussians at a time with Compress. With fewer than 16 lanes a row takes
  // several vectors (segments), and each pair has one list per segment, of the Gaussians whose
  // box also covers the segment's columns: the loop below then has no per-Gaussian column test,
  // a branch on the data that went either way (AVX2, syn200_20k: a tenth of the forward's time).
  // The same Gaussians in the same order reach each pixel.
  constexpr int kRowPairs = kTileSize / 2;
  const int segments = vectors_per_row;
  const int padded = (count + lanes - 1) / lanes * lanes;
  const std::size_t list_count = static_cast<std::size_t>(kRowPairs) * segments;
  std::int32_t* rows = list_scratch.Get((list_count + 4) * padded + 2 * lanes);
  std::int32_t* row0 = rows;
  std::int32_t* row1 = rows + padded;
  std::int32_t* col0 = rows + 2 * padded;  // filled and read only with several segments
  std::int32_t* col1 = rows + 3 * padded;
  std::int32_t* lists = rows + 4 * padded;  // kRowPairs x segments lists of `padded`
  // Structure-of-arrays copies of what the row test below needs.
  thread_local Scratch<float> soa_scratch;
  float* soa = soa_scratch.Get(static_cast<std::size_t>(7) * padded);
  float* s_mx = soa;  // mean x, mean y
  float* s_my = s_mx + padded;
  float* s_ha = s_my + padded;  // -a/2, -b, -c/2
  float* s_nb = s_ha + padded;
  float* s_hc = s_nb + padded;
  float* s_k = s_hc + padded;   // -b / a: the dx maximising power on a row is k dy
  float* s_thr = s_k + padded;  // log threshold; -inf: never pruned
  for (int j = 0; j < padded; ++j) {
    const float* r = j < count ? record(j) : nullptr;
    row0[j] = j < count ? box(j, kBoxRow0) : kTileSize;
    row1[j] = j < count ? box(j, kBoxRow1) : -1;
    if (segments > 1) {
      col0[j] = j < count ? box(j, kBoxCol0) : kTileSize;
      col1[j] = j < count ? box(j, kBoxCol1) : -1;
    }
    // Only when a > 0 (power concave in dx on a row) and the reach box is not the whole tile
    // because of an indefinite conic; otherwise all zeros, which the test never prunes.
    const bool exact = j < count && r[kRecHalfNegA] < 0.0f && std::isfinite(r[kRecHalfNegA]) &&
                       std::isfinite(r[kRecNegB]) && std::isfinite(r[kRecHalfNegC]);
    s_mx[j] = exact ? r[kRecMeanX] : 0.0f;
    s_my[j] = exact ? r[kRecMeanY] : 0.0f;
    s_ha[j] = exact ? r[kRecHalfNegA] : 0.0f;
    s_nb[j] = exact ? r[kRecNegB] : 0.0f;
    s_hc[j] = exact ? r[kRecHalfNegC] : 0.0f;
    // -b / a from the record's log2-unit terms: the row test's margin covers their rounding.
    s_k[j] = exact ? r[kRecNegB] / (-2.0f * r[kRecHalfNegA]) : 0.0f;
    // The power below which x = power + log2 o misses the floor.
    s_thr[j] = exact && std::isfinite(s_k[j]) ? kLogAlphaFloor - r[kRecLog2Opacity]
                                              : -std::numeric_limits<float>::infinity();
  }
  // Per pair of rows, also drop the Gaussians whose power stays below the log threshold on both
  // rows within the tile's columns: on row y the maximum of power over dx in [lo, hi] is at
  // clamp(k dy, lo, hi). lo and hi and dy are computed exactly as the kernel computes the lanes'
  // dx and dy, so every lane's (dx, dy) lies in the range tested; the margin covers the rounding
  // of both power evaluations (a few ulps of the sum of the absolute terms). The pruned
  // Gaussians reach no pixel of the pair, so the result is unchanged.
  const V px_first = hn::Set(d, static_cast<float>(x0) + 0.5f);
  const V px_last = hn::Set(d, static_cast<float>(x0) + static_cast<float>(kTileSize) - 0.5f);
  const auto row_reaches = [&](int j, int row) {
    const V mx = hn::Load(d, s_mx + j);
    const V lo = hn::Sub(mx, px_last);
    const V hi = hn::Sub(mx, px_first);
    const V dy = hn::Sub(hn::Load(d, s_my + j),
                         hn::Set(d, static_cast<float>(row) + 0.5f + static_cast<float>(y0)));
    const V ha = hn::Load(d, s_ha + j);
    const V nb = hn::Load(d, s_nb + j);
    const V hc = hn::Load(d, s_hc + j);
    const V dx = hn::Min(hn::Max(hn::Mul(hn::Load(d, s_k + j), dy), lo), hi);
    const V power =
        hn::MulAdd(dx, hn::MulAdd(ha, dx, hn::Mul(nb, dy)), hn::Mul(hn::Mul(hc, dy), dy));
    const V m = hn::Max(hn::Abs(lo), hn::Abs(hi));
    const V ady = hn::Abs(dy);
    const V size = hn::MulAdd(
        hn::Abs(ha), hn::Mul(m, m),
        hn::MulAdd(hn::Abs(nb), hn::Mul(m, ady), hn::Mul(hn::Abs(hc), hn::Mul(ady, ady))));
    const V margin = hn::MulAdd(size, hn::Set(d, 1e-5f), hn::Set(d, 1e-4f));
    // Not (power + margin < threshold): NaNs keep the Gaussian.
    return hn::Not(hn::Lt(hn::Add(power, margin), hn::Load(d, s_thr + j)));
  };
  // The first and last row each Gaussian reaches by both tests, for the backward.
  std::int32_t* tight_lo = nullptr;
  std::int32_t* tight_hi = nullptr;
  if constexpr (kKeep) {
    tight_lo = list_scratch2.Get(2 * static_cast<std::size_t>(padded));
    tight_hi = tight_lo + padded;
    for (int j = 0; j < padded; j += lanes) {
      hn::Store(hn::Set(di, kTileSize), di, tight_lo + j);
      hn::Store(hn::Set(di, -1), di, tight_hi + j);
    }
  }
  // Iota once (Highway 1.0.3 builds it through memory: a store-forwarding stall per call).
  const VI iota = hn::Iota(di, 0);
  int list_length[kRowPairs * kTileSize];  // [pair x segments + segment]
  for (int p = 0; p < kRowPairs; ++p) {
    std::int32_t* out = lists + p * segments * padded;
    int* n = list_length + p * segments;
    std::fill_n(n, segments, 0);
    const int ra = 2 * p, rb = 2 * p + 1;
    const VI row_a = hn::Set(di, ra), row_b = hn::Set(di, rb);
    for (int j = 0; j < padded; j += lanes) {
      // row0 <= row <= row1 (1.0.3 has no integer <=).
      const VI r0 = hn::Load(di, row0 + j);
      const VI r1 = hn::Load(di, row1 + j);
      auto in_a = hn::And(hn::Lt(r0, hn::Set(di, ra + 1)), hn::Gt(r1, hn::Set(di, ra - 1)));
      auto in_b = hn::And(hn::Lt(r0, hn::Set(di, rb + 1)), hn::Gt(r1, hn::Set(di, rb - 1)));
      if (hn::AllFalse(di, hn::Or(in_a, in_b))) continue;
      in_a = hn::And(in_a, hn::RebindMask(di, row_reaches(j, ra)));
      in_b = hn::And(in_b, hn::RebindMask(di, row_reaches(j, rb)));
      const auto m = hn::Or(in_a, in_b);
      const VI ids = hn::Add(iota, hn::Set(di, j));
      if (segments == 1) {
        StoreCompressed(ids, m, out + n[0]);
        n[0] += static_cast<int>(hn::CountTrue(di, m));
      } else {
        // col0 <= last column of the segment and col1 >= its first.
        const VI c0 = hn::Load(di, col0 + j);
        const VI c1 = hn::Load(di, col1 + j);
        for (int s = 0; s < segments; ++s) {
          const auto ms = hn::And(m, hn::And(hn::Lt(c0, hn::Set(di, (s + 1) * lanes)),
                                             hn::Gt(c1, hn::Set(di, s * lanes - 1))));
          StoreCompressed(ids, ms, out + s * padded + n[s]);
          n[s] += static_cast<int>(hn::CountTrue(di, ms));
        }
      }
      if constexpr (kKeep) {
        const VI lo = hn::Load(di, tight_lo + j);
        hn::Store(hn::Min(lo, hn::IfThenElse(in_a, row_a, hn::IfThenElse(in_b, row_b, lo))), di,
                  tight_lo + j);
        const VI hi = hn::Load(di, tight_hi + j);
        hn::Store(hn::Max(hi, hn::IfThenElse(in_b, row_b, hn::IfThenElse(in_a, row_a, hi))), di,
                  tight_hi + j);
      }
    }
  }
  // When the records stay in the state for the backward, narrow their rows (the forward below
  // reads only the columns). Rows cut here hold no pixel the Gaussian reaches.
  if constexpr (kKeep) {
    for (int j = 0; j < count; ++j) {
      float* r = rec + static_cast<std::size_t>(j) * stride;
      SetBox(r, channels, kBoxRow0, tight_lo[j]);
      SetBox(r, channels, kBoxRow1, tight_hi[j]);
    }
  }

  const V width = hn::Set(d, static_cast<float>(job.width - x0));
  const V height = hn::Set(d, static_cast<float>(job.height - y0));
  const V x_base = hn::Set(d, static_cast<float>(x0));
  const V y_base = hn::Set(d, static_cast<float>(y0));
  HWY_ALIGN float out_T[kTileSize];
  HWY_ALIGN std::int32_t out_n[kTileSize];
  HWY_ALIGN float out_c[(kC > 0 ? kC : 1) * kTileSize];

  const auto write = [&](int v, PixelState<kC>& st) {
    const int y = y0 + v * lanes / kTileSize;
    const int xs = x0 + v * lanes % kTileSize;
    const int n_valid = std::min(lanes, job.width - xs);
    const std::size_t row_start = static_cast<std::size_t>(y) * job.width;
#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
    // A whole row of 16 pixels of 3 or 6 channels: interleaved in registers, stored as vectors
    // (the scalar copy below took 8% of the forward on a trained 800x800 model).
    if constexpr (kC == 3 || kC == 6) {
      if (y < job.height && n_valid == lanes) {
        __m512 colour[kC];
        for (int c = 0; c < kC; ++c)
          colour[c] = hn::MulAdd(st.T, hn::Set(d, job.background[c]), st.acc[c]).raw;
        float* px_out = job.image + (row_start + xs) * kC;
        if constexpr (kC == 3) {
          StoreInterleaved3(colour, px_out);
        } else {
          StoreInterleaved6(colour, px_out);
        }
        hn::StoreU(st.T, d, job.final_T + row_start + xs);
        if constexpr (kKeep) hn::StoreU(st.last, di, job.n_contrib + row_start + xs);
        return;
      }
    }
#endif
    float* out_color = kC > 0 ? out_c : st.acc_mem;
    for (int c = 0; c < channels; ++c) {
      const V bg = hn::Set(d, job.background[c]);
      if constexpr (kC > 0) {
        hn::Store(hn::MulAdd(st.T, bg, st.acc[c]), d, out_color + c * lanes);
      } else {
        float* a = st.acc_mem + c * lanes;
        hn::Store(hn::MulAdd(st.T, bg, hn::Load(d, a)), d, a);
      }
    }
    hn::Store(st.T, d, out_T);
    if constexpr (kKeep) hn::Store(st.last, di, out_n);
    if (y >= job.height) return;
    for (int i = 0; i < n_valid; ++i) {
      const std::size_t pix = row_start + xs + i;
      job.final_T[pix] = out_T[i];
      if constexpr (kKeep) job.n_contrib[pix] = out_n[i];
      float* px_out = job.image + pix * channels;
      for (int c = 0; c < channels; ++c) px_out[c] = out_color[c * lanes + i];
    }
  };

  for (int pair = 0; pair < kRowPairs; ++pair) {
    if (y0 + 2 * pair >= job.height) break;
    for (int segment = 0; segment < segments; ++segment) {
      const int which = pair * segments + segment;
      const std::int32_t* list = lists + which * padded;
      const int va = 2 * pair * vectors_per_row + segment;
      const int vb = va + vectors_per_row;
      const V pxa = hn::Load(d, kOffsets.x + va * lanes);
      const V pya = hn::Load(d, kOffsets.y + va * lanes);
      const V pyb = hn::Load(d, kOffsets.y + vb * lanes);
      const M valid_x = hn::Lt(pxa, width);
      if (hn::AllFalse(d, valid_x)) continue;
      const V px = hn::Add(pxa, x_base);
      const V py_a = hn::Add(pya, y_base);
      const V py_b = hn::Add(pyb, y_base);
      PixelState<kC> a, b;
      a.T = b.T = hn::Set(d, 1.0f);
      a.last = b.last = hn::Zero(di);
      a.done = hn::Not(hn::And(valid_x, hn::Lt(pya, height)));
      b.done = hn::Not(hn::And(valid_x, hn::Lt(pyb, height)));
      if constexpr (kC > 0) {
        for (int c = 0; c < kC; ++c) a.acc[c] = b.acc[c] = hn::Zero(d);
        a.acc_mem = b.acc_mem = nullptr;
      } else {
        a.acc_mem = acc_mem;
        b.acc_mem = acc_mem + static_cast<std::size_t>(channels) * lanes;
        for (int c = 0; c < 2 * channels; ++c) hn::Store(hn::Zero(d), d, acc_mem + c * lanes);
      }
      for (int i = 0; i < list_length[which]; ++i) {
        const int j = list[i];
        const float* r = record(j);
        BlendStep<kC, kKeep>(r, j, channels, px, py_a, a);
        BlendStep<kC, kKeep>(r, j, channels, px, py_b, b);
        // Tested every step, and on `done` alone: a first test of whether any pixel stopped at
        // this step (to skip the second) was a branch on the data, mispredicted at every stop,
        // and cost the forward 11% (a real 800x800 model's views, docs/history/real-run-speed.md).
        if (hn::AllTrue(d, hn::And(a.done, b.done))) break;
      }
      write(va, a);
      write(vb, b);
    }
  }
}

// The backward sums, per pixel vector, u = o G dL/dalpha and its moments in the slot positions
// below; FinishSlot turns them into the slot's gradients (mean, conic, opacity) in place.
constexpr int kSumUdx = kSlotMean;
constexpr int kSumUdy = kSlotMean + 1;
constexpr int kSumUdxdx = kSlotConic;
constexpr int kSumUdxdy = kSlotConic + 1;
constexpr int kSumUdydy = kSlotConic + 2;
constexpr int kSumU = kSlotOpacity;

// With power = -a dx^2 / 2 - b dx dy - c dy^2 / 2 (natural units), alpha = o G and u = o G
// dL/dalpha: dL/dopacity = (sum u) / o, dL/dmean = sum u dpower/dmean, dL/dconic = sum u
// dpower/dconic. (The kernel has o G = 2^(power + log2 o) at hand, not G; o > 0 wherever a
// Gaussian reaches a pixel.) neg_a and neg_c: the natural -a and -c (from the splats' conic).
HWY_INLINE void FinishSlot(const float* r, float neg_a, float neg_c, float* slot) {
  const float o = r[kRecOpacity];
  const float neg_b = r[kRecNegB] * kLn2;  // the natural -b
  const float sx = slot[kSumUdx], sy = slot[kSumUdy];
  const float sxx = slot[kSumUdxdx], sxy = slot[kSumUdxdy], syy = slot[kSumUdydy];
  slot[kSlotMean] = neg_a * sx + neg_b * sy;
  slot[kSlotMean + 1] = neg_c * sy + neg_b * sx;
  slot[kSlotConic] = -0.5f * sxx;
  slot[kSlotConic + 1] = -sxy;
  slot[kSlotConic + 2] = -0.5f * syy;
  slot[kSlotOpacity] = slot[kSumU] / o;
}

// w ShareScale (blend.h) for a pixel vector: the Gaussian's colours f_c (kShareChannels
// broadcasts) times the planes of ShareInverse(C_c) at `inverse` (kTilePixels apart), as the
// scalar path computes f_c / C_c. Masked lanes have w = 0 and a finite scale.
HWY_INLINE V WeightTimesShareScale(D d, V w, const V* f, const float* inverse) {
  V scale = hn::Set(d, 1.0f);
  for (int c = 0; c < kShareChannels; ++c)
    scale = hn::Max(scale, hn::Mul(f[c], hn::Load(d, inverse + c * kTilePixels)));
  return hn::Mul(w, scale);
}

// A kernel long on purpose: the blend's backward is the costliest loop of a step
// (BM_RasterBackward); its per-Gaussian steps are the HWY_INLINE helpers above (FinishSlot ...).
template <int kC>
void BackwardTileImpl(const TileJob& job, int tile) {
  const D d;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int channels = kC > 0 ? kC : job.channels;
  const int stride = TileRecordStride(channels);
  const int slot_stride = SlotStride(channels);
  const int x0 = (tile % job.tiles_x) * kTileSize;
  const int y0 = (tile / job.tiles_x) * kTileSize;
  const int start = job.tile_ranges[tile];
  const int count = job.tile_ranges[tile + 1] - start;
  const int num_vectors = kTilePixels / lanes;

  // Per-pixel planes: T, the behind term (below), dL/dimage (channels), T_final g_T, n_contrib,
  // and with a geometry image its dL/dimage (channels), which dL/dalpha and g_T take instead.
  //
  // The behind colour b_c (what the Gaussians behind the current one add, per channel) enters
  // the gradients only as dL/dalpha = sum_c (f_c - b_c) dgeo_c, and its update b_c += alpha
  // (f_c - b_c) is linear, so one plane keeps B = sum_c b_c dgeo_c instead of one per channel:
  // dL/dalpha = F - B with F = sum_c f_c dgeo_c, and B += alpha (F - B). The same maths as the
  // scalar path's per-channel form (which the tests compare against), with other roundings.
  const bool split = job.dL_dimage_geometry != nullptr;
  // With a share image (--prune-radiance-share), kShareChannels planes of ShareInverse(C_c).
  const bool share = job.entry_max_weight != nullptr && job.share_image != nullptr;
  thread_local Scratch<float> plane_scratch;
  thread_local Scratch<float> rec_scratch;
  float* planes = plane_scratch.Get(
      static_cast<std::size_t>(kTilePixels) *
          (4 + (split ? 2 : 1) * channels + (share ? kShareChannels : 0)) +
      static_cast<std::size_t>(channels) * lanes);
  float* T_plane = planes;
  float* behind = T_plane + kTilePixels;
  float* dpix = behind + kTilePixels;
  float* tfb = dpix + static_cast<std::size_t>(kTilePixels) * channels;
  auto* nc_plane = reinterpret_cast<std::int32_t*>(tfb + kTilePixels);
  float* gf_mem = tfb + 2 * kTilePixels;  // feature gradients, run-time channel count only
  float* dgeo = split ? gf_mem + static_cast<std::size_t>(channels) * lanes : dpix;
  float* share_inv = gf_mem + static_cast<std::size_t>(channels) * lanes +
                     (split ? static_cast<std::size_t>(kTilePixels) * channels : 0);
  HWY_ALIGN std::int32_t vector_max[kTilePixels];
  // The planes hold the tile in blocks of block_w x block_h pixels, one pixel vector each (4x4
  // with 16 lanes, 4x2 with 8): a Gaussian reaching a few pixels of a few rows fills more of a
  // block's lanes than of a 16-pixel row's (counted in a real 200x200 run: 34% fewer vectors with
  // a reached lane than whole rows).
  const int block_w = std::min(lanes, 4);
  const int block_h = lanes / block_w;
  const int blocks_per_row = kTileSize / block_w;
  const auto plane_x = [&](int p) {
    return (p / lanes) % blocks_per_row * block_w + p % lanes % block_w;
  };
  const auto plane_y = [&](int p) {
    return (p / lanes) / blocks_per_row * block_h + p % lanes / block_w;
  };

  float* tile_bg = job.tile_background_grad != nullptr
                       ? job.tile_background_grad + static_cast<std::size_t>(tile) * channels
                       : nullptr;
  if (tile_bg != nullptr) std::fill(tile_bg, tile_bg + channels, 0.0f);
  int tile_max = 0;
  for (int v = 0; v < num_vectors; ++v) {
    int vmax = 0;
    for (int i = 0; i < lanes; ++i) {
      const int p = v * lanes + i;
      const int x = x0 + plane_x(p);
      const int y = y0 + plane_y(p);
      if (x >= job.width || y >= job.height) {
        T_plane[p] = 1.0f;
        tfb[p] = 0.0f;
        nc_plane[p] = 0;
        behind[p] = 0.0f;
        for (int c = 0; c < channels; ++c) {
          dpix[c * kTilePixels + p] = 0.0f;
          if (split) dgeo[c * kTilePixels + p] = 0.0f;
        }
        if (share)
          for (int c = 0; c < kShareChannels; ++c) share_inv[c * kTilePixels + p] = 0.0f;
        continue;
      }
      const std::size_t pix = static_cast<std::size_t>(y) * job.width + x;
      const float T_final = job.final_T[pix];
      const float* dL = job.dL_dimage + pix * channels;
      const float* dG = split ? job.dL_dimage_geometry + pix * channels : dL;
      for (int c = 0; c < channels; ++c) {
        if (tile_bg != nullptr) tile_bg[c] += T_final * dL[c];
        dpix[c * kTilePixels + p] = dL[c];
        if (split) dgeo[c * kTilePixels + p] = dG[c];  // else dgeo is dpix
      }
      if (share) {
        const float* C = job.share_image + pix * channels;
        for (int c = 0; c < kShareChannels; ++c)
          share_inv[c * kTilePixels + p] = ShareInverse(C[c]);
      }
      T_plane[p] = T_final;
      behind[p] = 0.0f;
      tfb[p] = job.dL_dfinal_T != nullptr ? job.dL_dfinal_T[pix] : 0.0f;  // g_T, below
      nc_plane[p] = job.n_contrib[pix];
      vmax = std::max(vmax, job.n_contrib[pix]);
    }
    vector_max[v] = vmax;
    tile_max = std::max(tile_max, vmax);
  }
  HDR4D_CHECK(tile_max <= count);
  // tfb = T_final g_T, g_T = dL/dT_final + sum_c background_c dgeo_c, per pixel vector from the
  // planes, in explicit multiply-adds. Not in the per-pixel loop above: GCC made more than one
  // version of that loop, vectorising the sum over channels in one (products rounded, then added
  // in order) and fusing each product into its add in another, and which ran depended on
  // whether a geometry image was passed: with one equal to dL/dimage the gradients differed in
  // the last bit (AVX2, 5 channels; issue 50). These are the same operations in every case.
  for (int v = 0; v < num_vectors; ++v) {
    const int off = v * lanes;
    V g_T = hn::Load(d, tfb + off);
    for (int c = 0; c < channels; ++c) {
      g_T = hn::MulAdd(hn::Set(d, job.background[c]), hn::Load(d, dgeo + c * kTilePixels + off),
                       g_T);
    }
    hn::Store(hn::Mul(hn::Load(d, T_plane + off), g_T), d, tfb + off);
  }

  // Entry start + j writes its slot at entry_slots[start + j] (per-Gaussian order).
  const std::int32_t* slot_index = job.entry_slots + start;
  const auto slot_of = [&](int j) {
    return job.entry_gradients + static_cast<std::size_t>(slot_index[j]) * slot_stride;
  };
  float* const max_weight = job.entry_max_weight;  // nullable, indexed like the slots
  for (int j = tile_max; j < count; ++j) {
    std::fill_n(slot_of(j), slot_stride, 0.0f);
    if (max_weight != nullptr) max_weight[slot_index[j]] = 0.0f;
  }
  const float* rec;
  if (job.tile_records_ready) {
    rec = job.tile_records + static_cast<std::size_t>(start) * stride;
  } else {
    float* own = rec_scratch.Get(static_cast<std::size_t>(tile_max) * stride + 1);
    GatherRecords<kC>(job, tile, start, tile_max, own);
    rec = own;
  }

  const V one = hn::Set(d, 1.0f);
  const V max_alpha = hn::Set(d, kMaxAlpha);
  const V min_alpha = hn::Set(d, kMinAlpha);
  const V log_alpha_floor = hn::Set(d, kLogAlphaFloor);
  // Pixel centres of the tile in plane order (the forward's values: k + 0.5 and the tile origin
  // are exact in float, so dx and dy are bit-equal).
  HWY_ALIGN float pixel_x[kTilePixels];
  HWY_ALIGN float pixel_y[kTilePixels];
  for (int p = 0; p < kTilePixels; ++p) {
    pixel_x[p] = kOffsets.x[plane_x(p)] + static_cast<float>(x0);
    pixel_y[p] = kOffsets.y[plane_y(p) * kTileSize] + static_cast<float>(y0);
  }
  constexpr int kGradCount = kSlotFeatures + (kC > 0 ? kC : 0);

  // The conic row (read after the pixels) and the gradient slot (written then) of each Gaussian
  // are at random places: prefetch them a few Gaussians ahead (the conic load was a tenth of this
  // kernel's time in a 200x200 run).
  constexpr int kAhead = 4;
  for (int j = tile_max - 1; j >= 0; --j) {
    if (j >= kAhead) {
      __builtin_prefetch(job.conic +
                         3 * static_cast<std::size_t>(job.point_list[start + j - kAhead]));
      __builtin_prefetch(slot_of(j - kAhead), 1);
    }
    const float* r = rec + static_cast<std::size_t>(j) * stride;
    const VI jv = hn::Set(di, j);
    const V mean_x = hn::Set(d, r[kRecMeanX]);
    const V mean_y = hn::Set(d, r[kRecMeanY]);
    const V log2o = hn::Set(d, r[kRecLog2Opacity]);
    V grad[kGradCount];
    for (int k = 0; k < kGradCount; ++k) grad[k] = hn::Zero(d);
    V w_max = hn::Zero(d);  // the largest blending weight, kept only with max_weight
    V share_f[kShareChannels];  // the Gaussian's colour in the share's channels
    if (share)
      for (int c = 0; c < kShareChannels; ++c) share_f[c] = hn::Set(d, r[kRecFeatures + c]);
    if constexpr (kC == 0) {
      for (int c = 0; c < channels; ++c) hn::Store(hn::Zero(d), d, gf_mem + c * lanes);
    }
    bool any = false;
    // Only the blocks of the rows and columns it can reach.
    const int row0 = Box(r, channels, kBoxRow0);
    const int row1 = Box(r, channels, kBoxRow1);
    const int bx0 = Box(r, channels, kBoxCol0) / block_w;
    const int bx1 = Box(r, channels, kBoxCol1) / block_w;
    const int by1 = row1 >= row0 ? row1 / block_h : -1;
    for (int by = row0 / block_h; by <= by1; ++by)
      for (int bx = bx0; bx <= bx1; ++bx) {
        const int vi = by * blocks_per_row + bx;
        if (vector_max[vi] <= j) continue;
        const int off = vi * lanes;
        const V dx = hn::Sub(mean_x, hn::Load(d, pixel_x + off));
        const V dy = hn::Sub(mean_y, hn::Load(d, pixel_y + off));
        const V x = PowerPlusLog2Opacity(r, dx, dy, log2o);  // log2 of the unclamped alpha
        const M listed = hn::RebindMask(d, hn::Lt(jv, hn::Load(di, nc_plane + off)));
        const M reach = hn::And(listed, hn::Ge(x, log_alpha_floor));
        if (hn::AllFalse(d, reach)) continue;
        // Unclamped: lanes outside m may hold garbage (even inf or NaN) in oG, alpha and inv; every
        // use below is masked by m (T, behind, w) or multiplied into u under IfThenElseZero.
        const V oG = FastExp2UnclampedV(d, x);  // opacity G, alpha before the clamp
        const V alpha = hn::Min(max_alpha, oG);
        const M m = hn::And(reach, hn::And(hn::Le(x, log2o), hn::Ge(alpha, min_alpha)));
        // (no early exit when m is empty: rare once reach holds, and masked below)
        any = true;
        const V inv = hn::Div(one, hn::Sub(one, alpha));
        const V T_old = hn::Load(d, T_plane + off);
        const V T = hn::Mul(T_old, inv);  // transmittance in front of this Gaussian
        hn::Store(hn::IfThenElse(m, T, T_old), d, T_plane + off);
        const V w = hn::IfThenElseZero(m, hn::Mul(alpha, T));
        if (max_weight != nullptr)
          w_max = hn::Max(w_max, share ? WeightTimesShareScale(d, w, share_f, share_inv + off) : w);
        V F = hn::Zero(d);
        for (int c = 0; c < channels; ++c) {
          const V dp = hn::Load(d, dpix + c * kTilePixels + off);
          F = hn::MulAdd(hn::Set(d, r[kRecFeatures + c]),
                         split ? hn::Load(d, dgeo + c * kTilePixels + off) : dp, F);
          if constexpr (kC > 0) {
            grad[kSlotFeatures + c] = hn::MulAdd(w, dp, grad[kSlotFeatures + c]);
          } else {
            float* gp = gf_mem + c * lanes;
            hn::Store(hn::MulAdd(w, dp, hn::Load(d, gp)), d, gp);
          }
        }
        const V B = hn::Load(d, behind + off);
        const V dL_dalpha = hn::Sub(F, B);
        // B for the Gaussians in front of this one.
        hn::Store(hn::IfThenElse(m, hn::MulAdd(alpha, dL_dalpha, B), B), d, behind + off);
        // u = o G dL/dalpha. The per-Gaussian factors (1/opacity, the conic terms, -1/2) come out
        // of the sums over pixels, so per pixel vector only the sums of u, u dx, u dy, u dx^2, u dx
        // dy and u dy^2 are kept; FinishSlot applies the factors once per Gaussian and tile.
        const V u = hn::IfThenElseZero(
            m, hn::Mul(oG, hn::NegMulAdd(hn::Load(d, tfb + off), inv, hn::Mul(dL_dalpha, T))));
        const V udx = hn::Mul(u, dx);
        const V udy = hn::Mul(u, dy);
        grad[kSumU] = hn::Add(grad[kSumU], u);
        grad[kSumUdx] = hn::Add(grad[kSumUdx], udx);
        grad[kSumUdy] = hn::Add(grad[kSumUdy], udy);
        grad[kSumUdxdx] = hn::MulAdd(udx, dx, grad[kSumUdxdx]);
        grad[kSumUdxdy] = hn::MulAdd(udx, dy, grad[kSumUdxdy]);
        grad[kSumUdydy] = hn::MulAdd(udy, dy, grad[kSumUdydy]);
      }
    float* slot = slot_of(j);
    if (max_weight != nullptr)
      max_weight[slot_index[j]] = any ? hn::GetLane(hn::MaxOfLanes(d, w_max)) : 0.0f;
    if (!any) {
      std::fill(slot, slot + slot_stride, 0.0f);
      continue;
    }
    ReduceLanes<kGradCount>(grad, slot);
    const float* conic = job.conic + 3 * static_cast<std::size_t>(job.point_list[start + j]);
    FinishSlot(r, -conic[0], -conic[2], slot);
    if constexpr (kC == 0) {
      for (int c = 0; c < channels; ++c)
        slot[kSlotFeatures + c] = hn::GetLane(hn::SumOfLanes(d, hn::Load(d, gf_mem + c * lanes)));
    }
  }
}

template <bool kKeep>
void ForwardTileKeeping(const TileJob& job, int tile) {
  switch (job.channels) {
    case 1:
      return ForwardTileImpl<1, kKeep>(job, tile);
    case 3:
      return ForwardTileImpl<3, kKeep>(job, tile);
    case 4:
      return ForwardTileImpl<4, kKeep>(job, tile);
    case 6:
      return ForwardTileImpl<6, kKeep>(job, tile);
    default:
      return ForwardTileImpl<0, kKeep>(job, tile);
  }
}

void ForwardTile(const TileJob& job, int tile) {
  if (job.tile_records != nullptr) return ForwardTileKeeping<true>(job, tile);
  ForwardTileKeeping<false>(job, tile);
}

void BackwardTile(const TileJob& job, int tile) {
  switch (job.channels) {
    case 1:
      return BackwardTileImpl<1>(job, tile);
    case 3:
      return BackwardTileImpl<3>(job, tile);
    case 4:
      return BackwardTileImpl<4>(job, tile);
    case 6:
      return BackwardTileImpl<6>(job, tile);
    default:
      return BackwardTileImpl<0>(job, tile);
  }
}

void PackTiles(const TileJob& job, std::int64_t begin, std::int64_t end) {
  PackSplats(job, begin, end);
}

// The tail goes through a zero-padded vector.
void FastExp2Array(const float* x, float* out, std::size_t n) {
  const D d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) hn::StoreU(FastExp2V(d, hn::LoadU(d, x + i)), d, out + i);
  if (i < n) {
    HWY_ALIGN float in_buf[kTileSize] = {};
    HWY_ALIGN float out_buf[kTileSize];
    std::copy(x + i, x + n, in_buf);
    hn::Store(FastExp2V(d, hn::Load(d, in_buf)), d, out_buf);
    std::copy(out_buf, out_buf + (n - i), out + i);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace hdr4d::method::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hdr4d::method {
namespace detail {

HWY_EXPORT(ForwardTile);
HWY_EXPORT(BackwardTile);
HWY_EXPORT(FastExp2Array);
HWY_EXPORT(PackTiles);

void ForwardTileSimd(const TileJob& job, int tile) { HWY_DYNAMIC_DISPATCH(ForwardTile)(job, tile); }
void BackwardTileSimd(const TileJob& job, int tile) {
  HWY_DYNAMIC_DISPATCH(BackwardTile)(job, tile);
}
void PackSplatsSimd(const TileJob& job, std::int64_t begin, std::int64_t end) {
  HWY_DYNAMIC_DISPATCH(PackTiles)(job, begin, end);
}
void FastExp2Simd(const float* x, float* out, std::size_t n) {
  HWY_DYNAMIC_DISPATCH(FastExp2Array)(x, out, n);
}

}  // namespace detail

void FastExp2(const float* x, float* out, std::size_t n) { detail::FastExp2Simd(x, out, n); }

}  // namespace hdr4d::method
#endif  // HWY_ONCE
