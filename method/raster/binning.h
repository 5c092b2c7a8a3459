// Binning of projected Gaussians to 16x16 pixel tiles (ARCHITECTURE §4, §6), the first half of the
// 3DGS tile rasteriser: every Gaussian is listed in each tile its screen rectangle covers, and
// each tile's list is ordered front to back.
//
// Tile rectangle. 3DGS's getRect takes the mean in pixel-centre coordinates (pixel x centred at
// x) and covers tiles floor((m - r) / 16) .. ceil((m + r) / 16) (exclusive), clamped to the grid.
// We apply the same formula to corner-origin coordinates (pixel x centred at x + 0.5): tile k
// spans [16k, 16k + 16), and the Gaussian covers exactly the tiles whose span meets the open
// interval (m - r, m + r) on both axes. So every tile holding a pixel centre within r of the mean
// (per axis) is covered, and no tile without one: when m + r == 16k the first centre of tile k,
// 16k + 0.5, is already outside. A Gaussian with radius <= 0, a non-finite mean or an empty
// clipped rectangle is not listed at all (its cost is one test).
//
// With SplatBuffers::reach the half-widths are per axis (rx, ry), each at most the radius: the
// rectangle of the ellipse where alpha can reach 1/255 instead of the square of its widest axis
// (the "SnugBox" of Speedy-Splat, Hanson et al., CVPR 2025). The tiles it leaves out hold no
// pixel that blends, so images and gradients are unchanged. It drops 39% of the entries of a
// trained 800x800 model (large, tilted splats) and 4% at 200x200 / 20k (small splats, where the
// reach's one-pixel rounding margin is most of the rectangle).
//
// Order. Entries are sorted by (tile, depth, Gaussian id): the visible Gaussians are first
// radix-sorted by depth (stable, so equal depths keep id order; depths compare by the total order
// of floats), then distributed to tiles with a counting sort that keeps that order. This equals
// sorting the 3DGS (tile | depth) keys with ties broken by id, with one sort of N keys instead of
// one of N x tiles keys. The result does not depend on the thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "method/raster/splats.h"

namespace hdr4d::method {

// Tiles [x0, x1) x [y0, y1) covered by a Gaussian (see above); empty when x0 >= x1 or y0 >= y1.
struct TileRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
  int area() const { return empty() ? 0 : (x1 - x0) * (y1 - y0); }
};
template <typename T>
TileRect GaussianTileRect(T mean_x, T mean_y, int radius_x, int radius_y, int tiles_x, int tiles_y);
template <typename T>
TileRect GaussianTileRect(T mean_x, T mean_y, int radius, int tiles_x, int tiles_y) {
  return GaussianTileRect(mean_x, mean_y, radius, radius, tiles_x, tiles_y);
}

// Number of tiles along an image side of `pixels` pixels.
int TileCount(int pixels);

// Sorts (keys[i], ids[i]) by key, stably (equal keys keep their order), with keys_tmp and ids_tmp
// as scratch; the same permutation at any thread count. The binning's depth order.
void RadixSortByKey(std::vector<std::uint32_t>& keys,
                    std::vector<std::int32_t>& ids,
                    std::vector<std::uint32_t>& keys_tmp,
                    std::vector<std::int32_t>& ids_tmp);

// Work that needs the tile rectangles (RasterState::rects) and the number of list entries but not
// the depth order: BinSplats runs it on the calling thread while the depth sort (serial below
// 65,536 visible Gaussians) runs beside it (RunAlongside), so that a second thread is not idle
// through the sort. It must not touch the binning's other buffers.
using BesideSort = std::function<void(std::int64_t entries)>;

// Fills the binning part of `state` (sizes, tile_ranges, point_list, depth_order, entry_ranges,
// point_entries) for `splats` on a settings.width x settings.height image, calling `beside_sort`
// (when given) as above. Inconsistent buffers or a non-positive image size are caller bugs
// (checked). Instantiated for float and double.
template <typename T>
void BinSplats(const SplatBuffersT<T>& splats,
               const RasterSettings& settings,
               RasterState* state,
               const BesideSort& beside_sort = nullptr);

}  // namespace hdr4d::method
