// Highway kernel of dense_simd.h, compiled for every x86 target Highway builds here.
//
// A register tile of up to 6 rows x 2 vectors of C: per k, two vectors of B's row k are loaded
// and each of the tile's A(i, k) broadcast into a multiply-add, so the tile's 12 accumulators
// stay in registers through the whole k loop (k is the layer's width forward, the batch's
// samples for the weight gradients). Columns past n are masked (27 basis outputs, 3 colours).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "baselines/hexplane/dense_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
// Must come after foreach_target.h.
#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>

#include "baselines/hexplane/dense_simd.h"

HWY_BEFORE_NAMESPACE();
namespace hdr4d::baselines::hexplane::dense_detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;

// The first `count` floats at p, the rest zero, never reading past them: AVX2's and AVX-512's
// masked loads do not touch masked lanes, while the scalar and emulated targets' MaskedLoad
// reads the whole vector, so those copy.
HWY_INLINE V LoadFirst(D d, const float* p, M mask, std::size_t count) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  (void)count;
  return hn::MaskedLoad(mask, d, p);
#else
  (void)mask;
  HWY_ALIGN float buffer[HWY_MAX_BYTES / sizeof(float)] = {};
  for (std::size_t i = 0; i < count; ++i) buffer[i] = p[i];
  return hn::Load(d, buffer);
#endif
}

struct Operands {
  int k;
  const float* a;
  std::ptrdiff_t a_row, a_col;
  const float* b;
  std::ptrdiff_t ldb;
  float* c;
  std::ptrdiff_t ldc;
  bool accumulate;
};

// The columns of a tile inside n: count0 of its first vector, count1 of its second.
struct Columns {
  M mask0, mask1;
  std::size_t count0, count1;
};

// C's two vectors of one row from the accumulators (plus C's own with o.accumulate).
template <bool kFull>
HWY_INLINE void StoreRow(const Operands& o, float* c, V acc0, V acc1, const Columns& cols) {
  const D d;
  const std::size_t N = hn::Lanes(d);
  if (kFull) {
    if (o.accumulate) {
      acc0 = hn::Add(acc0, hn::LoadU(d, c));
      acc1 = hn::Add(acc1, hn::LoadU(d, c + N));
    }
    hn::StoreU(acc0, d, c);
    hn::StoreU(acc1, d, c + N);
    return;
  }
  if (o.accumulate) {
    acc0 = hn::Add(acc0, LoadFirst(d, c, cols.mask0, cols.count0));
    acc1 = hn::Add(acc1, LoadFirst(d, c + N, cols.mask1, cols.count1));
  }
  hn::BlendedStore(acc0, cols.mask0, d, c);
  hn::BlendedStore(acc1, cols.mask1, d, c + N);
}

// Rows i0..i0+rows-1 (rows <= kTileRows) and columns j0..j0+2N-1 of C (kFull: all inside n).
// The accumulators are named variables, not an array: GCC keeps those in registers (an array
// of vectors went to the stack). A tile of fewer rows repeats its first row's A (not stored).
constexpr int kTileRows = 6;

template <bool kFull>
HWY_INLINE void Tile(const Operands& o, int i0, int rows, int j0, const Columns& cols) {
  const D d;
  const std::size_t N = hn::Lanes(d);
  const float* a[kTileRows];
  for (int r = 0; r < kTileRows; ++r) a[r] = o.a + (i0 + (r < rows ? r : 0)) * o.a_row;
  const float *a0 = a[0], *a1 = a[1], *a2 = a[2], *a3 = a[3], *a4 = a[4], *a5 = a[5];
  V c00 = hn::Zero(d), c01 = c00, c10 = c00, c11 = c00, c20 = c00, c21 = c00;
  V c30 = c00, c31 = c00, c40 = c00, c41 = c00, c50 = c00, c51 = c00;
  const float* b = o.b + j0;
  for (std::ptrdiff_t off = 0, end = std::ptrdiff_t(o.k) * o.a_col; off != end;
       off += o.a_col, b += o.ldb) {
    const V b0 = kFull ? hn::LoadU(d, b) : LoadFirst(d, b, cols.mask0, cols.count0);
    const V b1 = kFull ? hn::LoadU(d, b + N) : LoadFirst(d, b + N, cols.mask1, cols.count1);
    V av = hn::Set(d, a0[off]);
    c00 = hn::MulAdd(av, b0, c00), c01 = hn::MulAdd(av, b1, c01);
    av = hn::Set(d, a1[off]);
    c10 = hn::MulAdd(av, b0, c10), c11 = hn::MulAdd(av, b1, c11);
    av = hn::Set(d, a2[off]);
    c20 = hn::MulAdd(av, b0, c20), c21 = hn::MulAdd(av, b1, c21);
    av = hn::Set(d, a3[off]);
    c30 = hn::MulAdd(av, b0, c30), c31 = hn::MulAdd(av, b1, c31);
    av = hn::Set(d, a4[off]);
    c40 = hn::MulAdd(av, b0, c40), c41 = hn::MulAdd(av, b1, c41);
    av = hn::Set(d, a5[off]);
    c50 = hn::MulAdd(av, b0, c50), c51 = hn::MulAdd(av, b1, c51);
  }
  float* c = o.c + i0 * o.ldc + j0;
  StoreRow<kFull>(o, c, c00, c01, cols);
  if (rows > 1) StoreRow<kFull>(o, c + o.ldc, c10, c11, cols);
  if (rows > 2) StoreRow<kFull>(o, c + 2 * o.ldc, c20, c21, cols);
  if (rows > 3) StoreRow<kFull>(o, c + 3 * o.ldc, c30, c31, cols);
  if (rows > 4) StoreRow<kFull>(o, c + 4 * o.ldc, c40, c41, cols);
  if (rows > 5) StoreRow<kFull>(o, c + 5 * o.ldc, c50, c51, cols);
}

HWY_INLINE void RowBlock(const Operands& o, int i0, int rows, int n, const Columns& full) {
  const D d;
  const int N = int(hn::Lanes(d));
  int j = 0;
  for (; j + 2 * N <= n; j += 2 * N) Tile<true>(o, i0, rows, j, full);
  if (j == n) return;
  const std::size_t count0 = std::size_t(std::min(n - j, N));
  const std::size_t count1 = std::size_t(std::max(n - j - N, 0));
  Tile<false>(o, i0, rows, j, {hn::FirstN(d, count0), hn::FirstN(d, count1), count0, count1});
}

// Row blocks outermost (a row block of A stays in L1 while B's columns pass), k in blocks of
// kBlockK (a weight gradient's k is the batch's samples: B's block stays in L2 for every row).
constexpr int kBlockK = 256;

void Product(int m, int n, int k, const float* a, std::ptrdiff_t a_row, std::ptrdiff_t a_col,
             const float* b, std::ptrdiff_t ldb, float* c, std::ptrdiff_t ldc, bool accumulate) {
  const D d;
  const std::size_t N = hn::Lanes(d);
  const Columns full{hn::FirstN(d, N), hn::FirstN(d, N), N, N};
  int k0 = 0;
  do {
    const int kb = std::min(kBlockK, k - k0);
    const Operands o{kb, a + k0 * a_col, a_row, a_col, b + k0 * ldb, ldb, c, ldc,
                     accumulate || k0 > 0};
    for (int i = 0; i < m; i += kTileRows) RowBlock(o, i, std::min(kTileRows, m - i), n, full);
    k0 += kb;
  } while (k0 < k);
}

}  // namespace HWY_NAMESPACE
}  // namespace hdr4d::baselines::hexplane::dense_detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hdr4d::baselines::hexplane {
namespace dense_detail {
HWY_EXPORT(Product);
}  // namespace dense_detail

void DenseProduct(int m, int n, int k, const float* a, std::ptrdiff_t a_row, std::ptrdiff_t a_col,
                  const float* b, std::ptrdiff_t ldb, float* c, std::ptrdiff_t ldc,
                  bool accumulate) {
  if (m <= 0 || n <= 0) return;
  HWY_DYNAMIC_DISPATCH(dense_detail::Product)(m, n, std::max(k, 0), a, a_row, a_col, b, ldb, c,
                                              ldc, accumulate);
}

}  // namespace hdr4d::baselines::hexplane
#endif  // HWY_ONCE
