#include "method/raster/binning.h"

#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/scratch_vector.h"
#include "method/gaussian/constants.h"

namespace hdr4d::method {
namespace {

// Maps a float to an unsigned key with the same order (negative values flipped entirely, positive
// ones get the sign bit), so depths sort as integers.
std::uint32_t DepthKey(float depth) {
  const auto bits = std::bit_cast<std::uint32_t>(depth);
  return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

// Stable LSD radix sort of (key, id) pairs by key, three passes of 11/11/10 bits; a pass whose
// digit is the same for every key is skipped (common for the high bits of depths in one range).
// From kParallelSortMin pairs on, each pass counts and scatters fixed chunks in parallel: a
// chunk's pairs of one digit go, in their order, after the earlier chunks' pairs of that digit,
// which is the serial pass's permutation exactly.
constexpr int kSortPasses = 3;
constexpr std::array<int, kSortPasses> kSortShift = {0, 11, 22};
constexpr int kSortBuckets = 2048;
constexpr std::size_t kSortChunk = std::size_t{1} << 15;  // pairs per chunk of a parallel pass
constexpr std::size_t kParallelSortMin = 2 * kSortChunk;

std::uint32_t Digit(std::uint32_t key, int pass) {
  return (key >> kSortShift[pass]) & (kSortBuckets - 1);
}

// One pass in parallel chunks; false (nothing moved) when every key has the same digit.
bool ParallelRadixPass(int pass,
                       std::vector<std::uint32_t>& keys,
                       std::vector<std::int32_t>& ids,
                       std::vector<std::uint32_t>& keys_tmp,
                       std::vector<std::int32_t>& ids_tmp) {
  const std::size_t n = keys.size();
  const std::size_t chunks = (n + kSortChunk - 1) / kSortChunk;
  std::vector<std::array<std::uint32_t, kSortBuckets>> next(chunks);
  ParallelFor(static_cast<std::int64_t>(chunks), 1, [&](std::int64_t c) {
    auto& h = next[c];
    h.fill(0);
    const std::size_t end = std::min(n, (c + 1) * kSortChunk);
    for (std::size_t i = c * kSortChunk; i < end; ++i) ++h[Digit(keys[i], pass)];
  });
  const std::uint32_t first = Digit(keys[0], pass);
  std::size_t same = 0;
  for (const auto& h : next) same += h[first];
  if (same == n) return false;
  std::uint32_t sum = 0;
  for (int b = 0; b < kSortBuckets; ++b) {
    for (auto& h : next) {
      const std::uint32_t count = h[b];
      h[b] = sum;
      sum += count;
    }
  }
  ParallelFor(static_cast<std::int64_t>(chunks), 1, [&](std::int64_t c) {
    auto& h = next[c];
    const std::size_t end = std::min(n, (c + 1) * kSortChunk);
    for (std::size_t i = c * kSortChunk; i < end; ++i) {
      const std::uint32_t pos = h[Digit(keys[i], pass)]++;
      keys_tmp[pos] = keys[i];
      ids_tmp[pos] = ids[i];
    }
  });
  return true;
}

}  // namespace

void RadixSortByKey(std::vector<std::uint32_t>& keys,
                    std::vector<std::int32_t>& ids,
                    std::vector<std::uint32_t>& keys_tmp,
                    std::vector<std::int32_t>& ids_tmp) {
  HDR4D_CHECK(ids.size() == keys.size());
  const std::size_t n = keys.size();
  keys_tmp.resize(n);
  ids_tmp.resize(n);
  if (n == 0) return;
  if (n >= kParallelSortMin && MaxThreads() > 1) {
    for (int p = 0; p < kSortPasses; ++p) {
      if (!ParallelRadixPass(p, keys, ids, keys_tmp, ids_tmp)) continue;
      keys.swap(keys_tmp);
      ids.swap(ids_tmp);
    }
    return;
  }
  std::array<std::array<std::uint32_t, kSortBuckets>, kSortPasses> hist{};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t k = keys[i];
    for (int p = 0; p < kSortPasses; ++p) ++hist[p][Digit(k, p)];
  }
  for (int p = 0; p < kSortPasses; ++p) {
    auto& h = hist[p];
    if (h[Digit(keys[0], p)] == n) continue;
    std::uint32_t sum = 0;
    for (auto& c : h) {
      const std::uint32_t count = c;
      c = sum;
      sum += count;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t pos = h[Digit(keys[i], p)]++;
      keys_tmp[pos] = keys[i];
      ids_tmp[pos] = ids[i];
    }
    keys.swap(keys_tmp);
    ids.swap(ids_tmp);
  }
}

namespace {

// Ints in a 64-byte cache line: per-thread counters and spare slots are this far apart.
constexpr int kLineInts = 16;
// The fewest visible Gaussians per chunk of the counting sort (a chunk costs a wake-up and a
// counter array).
constexpr int kMinBinChunk = 4096;

}  // namespace

int TileCount(int pixels) { return (pixels + kTileSize - 1) / kTileSize; }

template <typename T>
TileRect GaussianTileRect(
    T mean_x, T mean_y, int radius_x, int radius_y, int tiles_x, int tiles_y) {
  TileRect rect;
  if (radius_x <= 0 || radius_y <= 0 || !std::isfinite(mean_x) || !std::isfinite(mean_y))
    return rect;
  const T size = static_cast<T>(kTileSize);
  // floor / ceil by truncation after clamping to [-1, n + 1], so far-away means cannot overflow
  // the int conversion (and no libm call: the x86-64 baseline has no rounding instruction).
  const auto clamped = [](T v, int n) {
    return std::min(std::max(v, T(-1)), static_cast<T>(n + 1));
  };
  const auto lo = [&](T m, T r, int n) {
    const T v = clamped((m - r) / size, n);
    int i = static_cast<int>(v);
    i -= v < static_cast<T>(i);  // floor
    return std::min(std::max(i, 0), n);
  };
  const auto hi = [&](T m, T r, int n) {
    const T v = clamped((m + r) / size, n);
    int i = static_cast<int>(v);
    i += v > static_cast<T>(i);  // ceil
    return std::min(std::max(i, 0), n);
  };
  const T rx = static_cast<T>(radius_x);
  const T ry = static_cast<T>(radius_y);
  rect.x0 = lo(mean_x, rx, tiles_x);
  rect.x1 = hi(mean_x, rx, tiles_x);
  rect.y0 = lo(mean_y, ry, tiles_y);
  rect.y1 = hi(mean_y, ry, tiles_y);
  return rect;
}

namespace {

// Chunks large enough that a thread wake-up (tens of microseconds) pays for itself.
constexpr int kChunk = 8192;

// 1. Each Gaussian's tile rectangle, then the visible ones in index order with their depth keys,
//    both in parallel over fixed chunks (so the order does not depend on threads). Returns how
//    many are visible and how many tile entries they make (the sum of their rectangles' areas,
//    known before the depth order).
struct VisibleCount {
  int visible = 0;
  std::int64_t entries = 0;
};
template <typename T>
VisibleCount VisibleRectsAndDepthKeys(const SplatBuffersT<T>& splats, RasterState& s) {
  const int n = s.num_gaussians;
  const int tiles_x = s.tiles_x;
  const int tiles_y = s.tiles_y;
  const T* mean = splats.mean2d.data();
  const int* radius = splats.radius.data();
  const int* reach = splats.reach.empty() ? nullptr : splats.reach.data();
  const int n_chunks = (n + kChunk - 1) / kChunk;
  s.rects.resize(4 * static_cast<std::size_t>(n));
  s.chunk_visible.assign(static_cast<std::size_t>(n_chunks) + 1, 0);
  std::vector<std::int64_t> chunk_entries(static_cast<std::size_t>(n_chunks), 0);
  std::int32_t* rects = s.rects.data();
  ParallelForChunks(n, kChunk, [&](std::int64_t begin, std::int64_t end) {
    int count = 0;
    std::int64_t entries = 0;
    for (std::int64_t g = begin; g < end; ++g) {
      const int rx = reach ? reach[2 * g] : radius[g];
      const int ry = reach ? reach[2 * g + 1] : radius[g];
      const TileRect r = radius[g] <= 0 ? TileRect{}
                                        : GaussianTileRect<T>(mean[2 * g], mean[2 * g + 1], rx, ry,
                                                              tiles_x, tiles_y);
      const bool empty = r.empty();
      rects[4 * g] = r.x0;
      rects[4 * g + 1] = r.y0;
      rects[4 * g + 2] = empty ? r.x0 : r.x1;  // an empty rectangle has area 0
      rects[4 * g + 3] = empty ? r.y0 : r.y1;
      count += !empty;
      entries += r.area();
    }
    s.chunk_visible[begin / kChunk + 1] = count;
    chunk_entries[begin / kChunk] = entries;
  });
  VisibleCount result;
  for (int c = 0; c < n_chunks; ++c) {
    s.chunk_visible[c + 1] += s.chunk_visible[c];
    result.entries += chunk_entries[c];
  }
  const int visible = s.chunk_visible[n_chunks];
  result.visible = visible;
  s.sort_keys.resize(visible);
  s.depth_order.resize(visible);
  ParallelForChunks(n, kChunk, [&](std::int64_t begin, std::int64_t end) {
    int v = s.chunk_visible[begin / kChunk];
    for (std::int64_t g = begin; g < end; ++g) {
      if (rects[4 * g + 2] == rects[4 * g]) continue;
      s.sort_keys[v] = DepthKey(static_cast<float>(splats.depth[g]));
      s.depth_order[v] = static_cast<std::int32_t>(g);
      ++v;
    }
  });
  return result;
}

// 3. The visible Gaussians' rectangles in depth order: one gather with independent loads, so the
//    passes below stream instead of waiting on a random access per Gaussian.
void SortRects(int visible, RasterState& s) {
  s.sorted_rects.resize(4 * static_cast<std::size_t>(visible));
  std::int32_t* sorted = s.sorted_rects.data();
  const std::int32_t* rects = s.rects.data();
  const std::int32_t* order = s.depth_order.data();
  ParallelFor(visible, kChunk, [&](std::int64_t i) {
    const std::int32_t* r = rects + 4 * static_cast<std::size_t>(order[i]);
    for (int k = 0; k < 4; ++k) sorted[4 * i + k] = r[k];
  });
}

// 4. The counting sort by tile, keeping depth order. The depth-ordered list is cut into chunks
//    counted and scattered in parallel; within a tile, chunk c's entries follow chunk c - 1's,
//    so the result is the same for any number of chunks. Most Gaussians cover at most 2 x 2
//    tiles; for those both passes run without data-dependent branches (a loop of 1..4
//    iterations mispredicts), adding 0 or writing to a spare slot after index `total` for the
//    tiles a smaller rectangle lacks. Each chunk has its own spare slot and counters, a cache
//    line apart: a slot shared by the threads was written for nearly every Gaussian by both,
//    and the line's ping-pong made binning 100k Gaussians with 2 threads 2.7x slower than
//    with one.
class TileCountingSort {
 public:
  TileCountingSort(int visible, RasterState& s)
      : s_(s),
        visible_(visible),
        num_tiles_(s.num_tiles()),
        tiles_x_(s.tiles_x),
        chunks_(std::clamp(MaxThreads(), 1, std::max(1, visible / kMinBinChunk))),
        chunk_size_(visible == 0 ? 1 : (visible + chunks_ - 1) / chunks_),
        // Per chunk: num_tiles counters + 3 spare counters (see Scatter), rounded up to whole
        // cache lines.
        counters_((num_tiles_ + 3 + kLineInts - 1) / kLineInts * kLineInts),
        chunk_entries_(static_cast<std::size_t>(chunks_) + 1, 0) {}

  // Each chunk's entries per tile, then each (chunk, tile)'s first slot and the tiles' ranges,
  // and each chunk's first entry in depth order, from which Scatter writes entry_ranges. (A
  // serial prefix over all the Gaussians waited on rectangles the other core had gathered.)
  void Count(std::int64_t total) {
    s_.chunk_offsets.assign(static_cast<std::size_t>(chunks_) * counters_, 0);
    ParallelFor(chunks_, 1, [&](std::int64_t c) { CountChunk(c); });
    for (int c = 0; c < chunks_; ++c) chunk_entries_[c + 1] += chunk_entries_[c];
    HDR4D_CHECK(chunk_entries_[chunks_] == total);
    const int num_tiles = num_tiles_, chunks = chunks_, counters = counters_;
    s_.tile_ranges.resize(static_cast<std::size_t>(num_tiles) + 1);
    std::int32_t* tile_ranges = s_.tile_ranges.data();
    std::int32_t* offsets = s_.chunk_offsets.data();
    std::int32_t running = 0;
    for (int t = 0; t < num_tiles; ++t) {
      tile_ranges[t] = running;
      for (int c = 0; c < chunks; ++c) {
        std::int32_t& slot = offsets[static_cast<std::size_t>(c) * counters + t];
        const std::int32_t count = slot;
        slot = running;
        running += count;
      }
    }
    tile_ranges[num_tiles] = running;
    HDR4D_CHECK(running == total);
  }

  // Every entry to its slot (point_list), entry_ranges and, with `slots`, the backward's entry
  // slots.
  void Scatter(std::int64_t total, bool slots) {
    // + one spare slot per chunk, the first of a cache line of its own.
    const std::int64_t with_spares = total + static_cast<std::int64_t>(chunks_) * kLineInts;
    ResizeScratch(&s_.point_list, with_spares);
    ResizeScratch(&s_.point_entries, slots ? with_spares : 1);
    ResizeScratch(&s_.entry_slots, slots ? with_spares : 1);
    s_.entry_ranges.resize(static_cast<std::size_t>(visible_) + 1);
    ParallelFor(chunks_, 1, [&](std::int64_t c) { ScatterChunk(c, total, slots); });
    s_.entry_ranges[visible_] = static_cast<std::int32_t>(total);
    s_.point_list.resize(total);
    s_.point_entries.resize(slots ? total : 0);
    s_.entry_slots.resize(slots ? total : 0);
  }

 private:
  std::pair<int, int> ChunkBounds(std::int64_t c) const {
    return {static_cast<int>(c) * chunk_size_,
            std::min(visible_, static_cast<int>(c + 1) * chunk_size_)};
  }

  void CountChunk(std::int64_t c) {
    std::int32_t* counts = s_.chunk_offsets.data() + c * counters_;
    const std::int32_t* sorted = s_.sorted_rects.data();
    const int tiles_x = tiles_x_;
    const auto [begin, end] = ChunkBounds(c);
    std::int64_t entries = 0;
    for (int i = begin; i < end; ++i) {
      const std::int32_t* rect = sorted + 4 * static_cast<std::size_t>(i);
      const int w = rect[2] - rect[0];
      const int h = rect[3] - rect[1];
      const int t = rect[1] * tiles_x + rect[0];
      entries += w * h;
      if (w <= 2 && h <= 2) {
        const int dx = w > 1, dy = h > 1;
        counts[t] += 1;
        counts[t + dx] += dx;
        counts[t + dy * tiles_x] += dy;
        counts[t + dx + dy * tiles_x] += dx & dy;
        continue;
      }
      for (int ty = 0; ty < h; ++ty)
        for (int tx = 0; tx < w; ++tx) ++counts[t + ty * tiles_x + tx];
    }
    chunk_entries_[c + 1] = entries;
  }

  void ScatterChunk(std::int64_t c, std::int64_t total, bool slots) {
    std::int32_t* next = s_.chunk_offsets.data() + c * counters_;
    const std::int32_t spare = static_cast<std::int32_t>(total + c * kLineInts);
    const std::int32_t* sorted = s_.sorted_rects.data();
    const std::int32_t* order = s_.depth_order.data();
    std::int32_t* entry_ranges = s_.entry_ranges.data();
    std::int32_t* points = s_.point_list.data();
    std::int32_t* entries = s_.point_entries.data();
    std::int32_t* slots_of = s_.entry_slots.data();
    const int tiles_x = tiles_x_;
    const int num_tiles = num_tiles_;
    const auto [begin, end] = ChunkBounds(c);
    auto first = static_cast<std::int32_t>(chunk_entries_[c]);  // Gaussian i's first entry
    for (int i = begin; i < end; ++i) {
      const int g = order[i];
      const std::int32_t* rect = sorted + 4 * static_cast<std::size_t>(i);
      const int w = rect[2] - rect[0];
      const int h = rect[3] - rect[1];
      const int t = rect[1] * tiles_x + rect[0];
      entry_ranges[i] = first;
      // This Gaussian's tiles, row-major (only written with slots; else the spare slot).
      std::int32_t* own = entries + (slots ? first : 0);
      const std::int32_t own_first = first;
      first += w * h;
      if (w <= 2 && h <= 2) {
        // A missing tile uses its own spare counter (num_tiles + 0..2), so it neither waits on
        // nor delays the counter of a real tile; its entry goes to the spare slot.
        const int dx = w > 1, dy = h > 1;
        const auto put = [&](int tile, int k, int valid, int spare_counter) {
          const int counter = valid ? tile : num_tiles + spare_counter;
          const std::int32_t pos = valid ? next[counter] : spare;
          next[counter] += valid;
          points[pos] = g;
          if (!slots) return;
          (valid ? own[k] : entries[spare]) = pos;
          slots_of[pos] = valid ? own_first + k : spare;
        };
        put(t, 0, 1, 0);
        put(t + dx, 1, dx, 0);
        put(t + dy * tiles_x, w, dy, 1);
        put(t + dx + dy * tiles_x, w + 1, dx & dy, 2);
        continue;
      }
      int k = 0;
      for (int ty = 0; ty < h; ++ty) {
        for (int tx = 0; tx < w; ++tx) {
          const std::int32_t pos = next[t + ty * tiles_x + tx]++;
          points[pos] = g;
          if (!slots) continue;
          slots_of[pos] = own_first + k;
          own[k++] = pos;
        }
      }
    }
  }

  RasterState& s_;
  const int visible_, num_tiles_, tiles_x_, chunks_, chunk_size_, counters_;
  std::vector<std::int64_t> chunk_entries_;  // per chunk, then its first entry (Count)
};

}  // namespace

template <typename T>
void BinSplats(const SplatBuffersT<T>& splats,
               const RasterSettings& settings,
               RasterState* state,
               const BesideSort& beside_sort) {
  HDR4D_CHECK(state != nullptr);
  HDR4D_CHECK(settings.width > 0 && settings.height > 0);
  HDR4D_CHECK(splats.Validate().empty());
  HDR4D_CHECK(splats.size() < static_cast<std::size_t>(INT_MAX));
  RasterState& s = *state;
  s.width = settings.width;
  s.height = settings.height;
  s.tiles_x = TileCount(settings.width);
  s.tiles_y = TileCount(settings.height);
  s.num_gaussians = static_cast<int>(splats.size());
  s.packed_ready = false;
  const auto [visible, entries] = VisibleRectsAndDepthKeys(splats, s);
  HDR4D_CHECK(entries < INT_MAX);
  // 2. Front-to-back order of the visible Gaussians (ties by id: the sort is stable), with the
  // caller's work beside it.
  const auto sort = [&s] {
    RadixSortByKey(s.sort_keys, s.depth_order, s.sort_keys_tmp, s.sort_ids_tmp);
  };
  if (beside_sort) {
    RunAlongside(sort, [&] { beside_sort(entries); });
  } else {
    sort();
  }
  SortRects(visible, s);
  TileCountingSort tiles(visible, s);
  tiles.Count(entries);
  // The backward's entry slots are not built for a render no backward follows.
  tiles.Scatter(entries, /*slots=*/settings.keep_records);
}

template TileRect GaussianTileRect<float>(float, float, int, int, int, int);
template TileRect GaussianTileRect<double>(double, double, int, int, int, int);
template void BinSplats<float>(const SplatBuffersT<float>&,
                               const RasterSettings&,
                               RasterState*,
                               const BesideSort&);
template void BinSplats<double>(const SplatBuffersT<double>&,
                                const RasterSettings&,
                                RasterState*,
                                const BesideSort&);

}  // namespace hdr4d::method
