// The dense products of HexPlane's appearance (the MLP's layers and the basis matrix, forward
// and backward) in float SIMD: Highway, compiled for every x86 target it builds here (AVX-512,
// AVX2, the scalar baseline) and chosen at run time (HDR4D_SIMD_TARGETS limits the choice;
// method::ActiveSimdTarget names the one in use).
// Eigen, built for the baseline ISA, ran these with 128-bit vectors; they were two thirds of a
// training iteration (BENCHMARKS.md).
#pragma once

#include <cstddef>

namespace hdr4d::baselines::hexplane {

// C (m x n, rows ldc apart) = A B, or C += A B with `accumulate`, where A(i, k) is
// a[i * a_row + k * a_col] (a transposed A is a_row = 1, a_col = its row length) and B is k x n
// row-major with rows ldb apart. Deterministic (no threads; the same target gives the same bits),
// but the products are summed in another order than Eigen's: results agree to float rounding.
// m, n or k may be 0 (k = 0: C = 0, or unchanged with `accumulate`).
void DenseProduct(int m, int n, int k, const float* a, std::ptrdiff_t a_row, std::ptrdiff_t a_col,
                  const float* b, std::ptrdiff_t ldb, float* c, std::ptrdiff_t ldc,
                  bool accumulate);

}  // namespace hdr4d::baselines::hexplane
