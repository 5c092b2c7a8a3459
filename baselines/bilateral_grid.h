// A bilateral filter of a single-channel image by the bilateral grid (Paris & Durand 2006; Chen,
// Paris & Durand 2007), the acceleration used by the Durand tone mapper: each pixel is splatted
// with trilinear weights into a coarse 3D grid (x, y, guide value) whose spacing is the spatial
// sigma in x and y and the range sigma in the guide axis; the grid is blurred with a Gaussian of
// one cell (truncated at two cells, zero outside the grid) along each axis; each pixel then reads
// the grid back at its own position (the same trilinear weights), and the result is normalised
// by the same pipeline applied to a constant 1. The effective spatial kernel is a little wider
// than sigma (about 1.15 sigma: the trilinear tents add their own spread), as in those papers.
//
// The guide fixes every weight (grid positions, trilinear weights, normalisation); the filtered
// values enter linearly. So Filter is a linear map of the values, A v = (S^T B S v) / (S^T B S 1)
// with S the splat and B the (symmetric) blur, and FilterBackward applies its exact transpose
// S^T B S (g / (S^T B S 1)). For an edge-preserving filter of an image by itself (guide = values)
// FilterBackward is the gradient with the weights held constant.
//
// Deterministic at any thread count: the splat gathers, per grid row, the pixel rows that touch
// it in a fixed order; the blur and the read-back are independent per line and per pixel.
#pragma once

#include <cstdint>
#include <vector>

namespace hdr4d::baselines {

template <typename T>
class BilateralGrid {
 public:
  // guide: width x height values. sigma_space in pixels and sigma_range in guide units (both
  // > 0, checked). A non-finite guide value is placed at the grid's range origin (so indexing
  // stays safe); its NaN value, if filtered, spreads to its neighbours and stays visible.
  BilateralGrid(const T* guide, int width, int height, double sigma_space, double sigma_range);

  int width() const { return width_; }
  int height() const { return height_; }
  // Cells along x, y and the guide axis.
  int cells_x() const { return nx_; }
  int cells_y() const { return ny_; }
  int cells_z() const { return nz_; }

  // out = A values (width x height each; out may not alias values).
  void Filter(const T* values, T* out) const;
  // dL_dvalues = A^T dL_dout (overwritten; may not alias dL_dout).
  void FilterBackward(const T* dL_dout, T* dL_dvalues) const;

 private:
  // S^T B S v for a per-pixel v.
  void SplatBlurSlice(const T* v, T* out) const;

  int width_, height_;
  int nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<std::int32_t> ix_, iy_, iz_;  // lower cell per column, row, pixel
  std::vector<T> fx_, fy_, fz_;             // fractional position above that cell
  std::vector<std::int32_t> row_begin_;     // first pixel row whose lower cell is gy (ny_+1)
  std::vector<T> normaliser_;               // S^T B S 1 per pixel (> 0)
};

}  // namespace hdr4d::baselines
