// The data the tile rasteriser consumes and produces for one frame (ARCHITECTURE §4, §6): projected
// 2D Gaussians ("splats") as structure-of-arrays buffers, their gradients, the raster settings,
// and the state the forward keeps for the backward.
//
// Conventions every producer and consumer of these buffers must follow:
// - Pixel coordinates are corner-origin (core/geometry/camera.h): pixel (x, y) covers [x, x+1) x [y, y+1)
//   and its centre is (x + 0.5, y + 0.5).
// - A splat's 2D Gaussian at pixel centre p is G = exp(power) with d = mean2d - p and
//   power = -0.5 (a dx^2 + c dy^2) - b dx dy, where conic = (a, b, c) is the inverse 2D
//   covariance [[a, b], [b, c]].
// - Gradients are the exact partial derivatives of the loss with respect to each stored float.
//   In particular the conic gradient's middle component is dL/db for the scalar b of the formula
//   above, i.e. TWICE the value the 3DGS CUDA kernel stores in dL_dconic2D.y (which is the
//   derivative with respect to one of the two symmetric off-diagonal entries). The preprocess
//   backward must use it as dL/db.
// - Images are interleaved H x W x channels floats, index (y * W + x) * channels + c, like
//   hdr4d::Image.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hdr4d::method {

// N projected Gaussians of one frame, after preprocessing (slicing, projection, colour).
// Templated so that the scalar reference and the finite-difference tests can run in double;
// the production type is SplatBuffers (float).
template <typename T>
struct SplatBuffersT {
  int channels = 3;         // features per Gaussian (3 for one colour, 6 for HDR + LDR)
  std::vector<T> mean2d;    // N x 2: pixel coordinates of the projected mean
  std::vector<T> conic;     // N x 3: (a, b, c) of the inverse 2D covariance
  std::vector<T> opacity;   // N: opacity, already multiplied by the temporal marginal p(t)
  std::vector<T> depth;     // N: camera z, the sort key within a tile (front = small)
  std::vector<int> radius;  // N: screen radius in pixels; 0 = culled (costs nothing)
  std::vector<T> features;  // N x channels: the values blended (colours)
  // Optional, N x 2: per-axis binning radii (x, y), each <= radius, bounding where alpha can
  // reach 1/255 on that axis; the binning lists the tiles of that rectangle instead of the
  // square of `radius`. Empty: the square. Not touched by Resize (a producer that does not fill
  // it leaves it empty).
  std::vector<int> reach;

  std::size_t size() const { return opacity.size(); }
  // Resizes every buffer for n Gaussians (new entries zero, i.e. culled).
  void Resize(std::size_t n) {
    mean2d.resize(2 * n);
    conic.resize(3 * n);
    opacity.resize(n);
    depth.resize(n);
    radius.resize(n);
    features.resize(n * static_cast<std::size_t>(channels));
  }
  // "" when the buffers agree with size() and channels >= 1, else what is wrong.
  std::string Validate() const {
    const std::size_t n = size();
    if (channels < 1) return "channels must be >= 1";
    if (mean2d.size() != 2 * n) return "mean2d must hold 2 values per Gaussian";
    if (conic.size() != 3 * n) return "conic must hold 3 values per Gaussian";
    if (depth.size() != n) return "depth must hold 1 value per Gaussian";
    if (radius.size() != n) return "radius must hold 1 value per Gaussian";
    if (features.size() != n * static_cast<std::size_t>(channels))
      return "features must hold `channels` values per Gaussian";
    if (!reach.empty() && reach.size() != 2 * n)
      return "reach must be empty or hold 2 values per Gaussian";
    return "";
  }
};
using SplatBuffers = SplatBuffersT<float>;

// Gradients with the layouts of the matching SplatBuffers fields. The backward ACCUMULATES
// (+=) into them; an empty buffer is first resized to the right size, filled with zeros.
template <typename T>
struct SplatGradientsT {
  std::vector<T> mean2d;    // N x 2
  std::vector<T> conic;     // N x 3 (dL/da, dL/db, dL/dc; see the note at the top)
  std::vector<T> opacity;   // N
  std::vector<T> features;  // N x channels
  // Optional (--prune-contribution, issue 55): when sized N before a backward, the backward
  // raises each entry to the largest blending weight alpha T the Gaussian had at any pixel of the
  // frame (a max, not a sum; 0 where it blended nowhere), or with RasterSettings::share_image
  // the largest share (blend.h ShareScale). Empty: not tracked, no cost. SetZero leaves it alone.
  std::vector<T> max_weight;
  // Sizes every buffer for n Gaussians and sets it to zero (no reallocation when the size holds).
  void SetZero(std::size_t n, int channels) {
    mean2d.assign(2 * n, T(0));
    conic.assign(3 * n, T(0));
    opacity.assign(n, T(0));
    features.assign(n * static_cast<std::size_t>(channels), T(0));
  }
};
using SplatGradients = SplatGradientsT<float>;

// Which implementation blends: the scalar per-pixel reference (a port of the CUDA kernels, with
// std::exp) or the fast path vectorised over the pixels of a tile (Highway, runtime dispatch,
// polynomial exp). Both follow the same rules and bin identically; see blend.h for how far they
// may differ.
enum class RasterBackend { kScalar, kSimd };

struct RasterSettings {
  int width = 0;
  int height = 0;
  // One value per channel, composited as colour + T_final * background. Empty means zeros.
  std::vector<float> background;
  RasterBackend backend = RasterBackend::kSimd;
  // Keep what a backward of the same frame needs. false, for a render no backward follows:
  // binning skips the backward's entry slots (point_entries, entry_slots), the kSimd forward
  // reads the per-Gaussian records in place instead of writing the state's per-entry records
  // (~50 bytes per tile entry at 6 channels, written and read back once per frame), and
  // n_contrib is left empty. The images and final_transmittance are the same bit for bit; a
  // backward of such a frame is a caller bug (checked).
  bool keep_records = true;
  // Backward input, read only where SplatGradients::max_weight is tracked
  // (--prune-radiance-share): the forward's image (H x W x channels, channels >= 3). The value of a
  // Gaussian at a pixel is then its share of the pixel, alpha T ShareScale (blend.h): a faint
  // Gaussian that carries much of a pixel's radiance counts as much as it carries.
  const float* share_image = nullptr;
};

// Everything the backward needs from the forward, kept between the calls. One object is meant
// to be reused frame after frame: its buffers only grow, so a steady state does not allocate.
struct RasterState {
  // --- Written by BinSplats (binning.h). ---
  int width = 0;
  int height = 0;
  int tiles_x = 0;  // ceil(width / kTileSize)
  int tiles_y = 0;
  int num_gaussians = 0;
  // Tile t = ty * tiles_x + tx owns entries [tile_ranges[t], tile_ranges[t + 1]) of
  // `point_list`, which holds Gaussian ids sorted by (tile, depth, id): front to back.
  std::vector<std::int32_t> tile_ranges;  // tiles + 1
  std::vector<std::int32_t> point_list;   // one entry per (tile, Gaussian) overlap
  // The Gaussians listed in at least one tile, front to back (ties by id).
  std::vector<std::int32_t> depth_order;
  // The entries of depth_order[i], in ascending tile order, are
  // point_entries[entry_ranges[i] .. entry_ranges[i + 1]) (indices into point_list). The
  // backward sums per-entry gradients in this fixed order, so it is deterministic.
  std::vector<std::int32_t> entry_ranges;   // depth_order.size() + 1
  std::vector<std::int32_t> point_entries;  // same length as point_list
  // The inverse of point_entries: entry e of point_list is point_entries[entry_slots[e]]. The
  // SIMD backward writes entry e's gradient slot at position entry_slots[e], so that the
  // reduction reads each Gaussian's slots contiguously (same order, same sums).
  std::vector<std::int32_t> entry_slots;  // same length as point_list

  // --- Written by BlendForward (blend.h). ---
  std::vector<float> final_transmittance;  // H x W: T after the last contributing Gaussian
  // H x W: 1 + the position, within the pixel's tile list, of the last Gaussian that
  // contributed (0 = none), as n_contrib in the 3DGS kernels. The backward starts there.
  // Empty after a forward without keep_records.
  std::vector<std::int32_t> n_contrib;

  // --- Scratch reused between calls (contents meaningless outside a call). ---
  std::vector<std::int32_t> rects;           // binning: tile rectangle per Gaussian (x0 y0 x1 y1)
  std::vector<std::int32_t> sorted_rects;    // binning: the same in depth order
  std::vector<std::int32_t> chunk_visible;   // binning: visible Gaussians before each chunk
  std::vector<std::uint32_t> sort_keys;      // binning: depth keys of visible Gaussians
  std::vector<std::uint32_t> sort_keys_tmp;  // binning: radix sort ping-pong
  std::vector<std::int32_t> sort_ids_tmp;
  std::vector<std::int32_t> chunk_offsets;  // binning: per (chunk, tile) counters
  std::vector<float> packed_splats;         // kSimd forward: per-Gaussian kernel records, reused by
  bool packed_ready = false;                // the backward (reset by BinSplats, kScalar)
  std::vector<float> entry_gradients;       // backward: one gradient slot per entry
  std::vector<float> entry_max_weight;      // backward with max_weight: one value per entry
  std::vector<float> tile_background_grad;  // backward: dL/dbackground per tile

  int num_tiles() const { return tiles_x * tiles_y; }
  std::size_t num_entries() const { return point_list.size(); }
};

}  // namespace hdr4d::method
