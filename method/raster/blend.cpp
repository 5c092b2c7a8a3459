// The scalar reference blend (a per-pixel port of the 3DGS CUDA kernels, templated on the
// scalar type), the backend dispatch, and the deterministic gradient reduction shared by both
// backends. The vectorised kernels are in blend_simd.cpp.
#include "method/raster/blend.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/scratch_vector.h"
#include "method/gaussian/constants.h"
#include "method/raster/binning.h"

namespace hdr4d::method {
namespace {

using detail::SlotStride;

// A few values per pixel or per Gaussian, on the stack unless the channel count is unusual.
template <typename T>
class SmallBuffer {
 public:
  explicit SmallBuffer(int n) {
    if (n > static_cast<int>(stack_.size())) heap_.resize(n);
    data_ = heap_.empty() ? stack_.data() : heap_.data();
  }
  T& operator[](int i) { return data_[i]; }
  T* data() { return data_; }

 private:
  std::array<T, 32> stack_{};
  std::vector<T> heap_;
  T* data_;
};

struct TileBounds {
  int x0, y0, x1, y1;  // pixels [x0, x1) x [y0, y1) inside the image
};
TileBounds BoundsOf(const RasterState& bins, int tile) {
  const int tx = tile % bins.tiles_x;
  const int ty = tile / bins.tiles_x;
  TileBounds b;
  b.x0 = tx * kTileSize;
  b.y0 = ty * kTileSize;
  b.x1 = std::min(bins.width, b.x0 + kTileSize);
  b.y1 = std::min(bins.height, b.y0 + kTileSize);
  return b;
}

void CheckBinned(const RasterState& bins, std::size_t n) {
  HDR4D_CHECK(bins.width > 0 && bins.height > 0);
  HDR4D_CHECK(bins.num_gaussians == static_cast<int>(n));
  HDR4D_CHECK(static_cast<int>(bins.tile_ranges.size()) == bins.num_tiles() + 1);
  HDR4D_CHECK(bins.entry_ranges.size() == bins.depth_order.size() + 1);
}

// A backward needs the entry slots that a binning without keep_records leaves out.
void CheckBinnedForBackward(const RasterState& bins, std::size_t n) {
  CheckBinned(bins, n);
  HDR4D_CHECK(bins.entry_slots.size() == bins.point_list.size() &&
              bins.point_entries.size() == bins.point_list.size());
}

template <typename T>
void ForwardTileReference(const SplatBuffersT<T>& splats,
                          const RasterState& bins,
                          const T* background,
                          T* image,
                          T* final_T,
                          std::int32_t* n_contrib,
                          int tile) {
  const int channels = splats.channels;
  const TileBounds b = BoundsOf(bins, tile);
  const int start = bins.tile_ranges[tile];
  const int end = bins.tile_ranges[tile + 1];
  const T* mean = splats.mean2d.data();
  const T* conic = splats.conic.data();
  const T* opacity = splats.opacity.data();
  const T* features = splats.features.data();
  SmallBuffer<T> color(channels);
  for (int y = b.y0; y < b.y1; ++y) {
    for (int x = b.x0; x < b.x1; ++x) {
      const T px = static_cast<T>(x) + T(0.5);
      const T py = static_cast<T>(y) + T(0.5);
      for (int c = 0; c < channels; ++c) color[c] = T(0);
      T transmittance = T(1);
      int contributor = 0;
      int last = 0;
      for (int idx = start; idx < end; ++idx) {
        ++contributor;
        const int g = bins.point_list[idx];
        const T dx = mean[2 * g] - px;
        const T dy = mean[2 * g + 1] - py;
        const T* q = conic + 3 * g;
        const T power = T(-0.5) * (q[0] * dx * dx + q[2] * dy * dy) - q[1] * dx * dy;
        if (power > T(0)) continue;
        const T alpha = std::min(T(kMaxAlpha), opacity[g] * std::exp(power));
        if (alpha < T(kMinAlpha)) continue;
        const T test_T = transmittance * (T(1) - alpha);
        if (test_T < T(kMinTransmittance)) break;  // done; this Gaussian does not contribute
        const T* f = features + static_cast<std::size_t>(g) * channels;
        for (int c = 0; c < channels; ++c) color[c] += f[c] * alpha * transmittance;
        transmittance = test_T;
        last = contributor;
      }
      const std::size_t pix = static_cast<std::size_t>(y) * bins.width + x;
      final_T[pix] = transmittance;
      n_contrib[pix] = last;
      for (int c = 0; c < channels; ++c)
        image[pix * channels + c] = color[c] + transmittance * background[c];
    }
  }
}

// Zeroes what one tile of the reference backward writes: its entries' slots and, where kept,
// their largest blending weights and the tile's background partials.
template <typename T>
void ClearTileOutputs(int start, int end, int stride, int channels, T* slots, T* tile_bg,
                      T* weights) {
  std::fill(slots + static_cast<std::size_t>(start) * stride,
            slots + static_cast<std::size_t>(end) * stride, T(0));
  if (tile_bg != nullptr) std::fill(tile_bg, tile_bg + channels, T(0));
  if (weights != nullptr) std::fill(weights + start, weights + end, T(0));
}

// One pixel's gradient of a Gaussian's 2D mean, conic and opacity, from dL/dalpha through
// alpha = opacity x G, G = exp(power) (offset dx, dy from the pixel; conic q).
template <typename T>
void AddGeometrySlots(T opacity, T G, T dx, T dy, const T* q, T dL_dalpha, T* slot) {
  const T dL_dG = opacity * dL_dalpha;
  const T gdx = G * dx;
  const T gdy = G * dy;
  slot[detail::kSlotMean] += dL_dG * (-gdx * q[0] - gdy * q[1]);
  slot[detail::kSlotMean + 1] += dL_dG * (-gdy * q[2] - gdx * q[1]);
  slot[detail::kSlotConic] += T(-0.5) * gdx * dx * dL_dG;
  slot[detail::kSlotConic + 1] += -gdx * dy * dL_dG;
  slot[detail::kSlotConic + 2] += T(-0.5) * gdy * dy * dL_dG;
  slot[detail::kSlotOpacity] += G * dL_dalpha;
}

// One tile of the reference backward: fills the tile's entry slots (overwritten) and, when
// tile_bg is non-null, its channels partial sums of dL/dbackground.
template <typename T>
void BackwardTileReference(const SplatBuffersT<T>& splats,
                           const RasterState& bins,
                           const T* background,
                           const T* final_T,
                           const std::int32_t* n_contrib,
                           const T* dL_dimage,
                           const T* dL_dgeometry,
                           const T* dL_dfinal_T,
                           const T* share_image,
                           T* slots,
                           T* tile_bg,
                           T* weights,
                           int tile) {
  const int channels = splats.channels;
  const int stride = SlotStride(channels);
  const TileBounds b = BoundsOf(bins, tile);
  const int start = bins.tile_ranges[tile];
  const int end = bins.tile_ranges[tile + 1];
  ClearTileOutputs(start, end, stride, channels, slots, tile_bg, weights);
  const T* mean = splats.mean2d.data();
  const T* conic = splats.conic.data();
  const T* opacity = splats.opacity.data();
  const T* features = splats.features.data();
  SmallBuffer<T> accum(channels);
  SmallBuffer<T> last_color(channels);
  for (int y = b.y0; y < b.y1; ++y) {
    for (int x = b.x0; x < b.x1; ++x) {
      const std::size_t pix = static_cast<std::size_t>(y) * bins.width + x;
      const T px = static_cast<T>(x) + T(0.5);
      const T py = static_cast<T>(y) + T(0.5);
      const T* dpix = dL_dimage + pix * channels;
      const T* gpix = dL_dgeometry + pix * channels;  // what dL/dalpha takes
      const T T_final = final_T[pix];
      // Everything the final transmittance multiplies: the background and its own gradient.
      T dL_dT_final = dL_dfinal_T != nullptr ? dL_dfinal_T[pix] : T(0);
      for (int c = 0; c < channels; ++c) {
        dL_dT_final += background[c] * gpix[c];
        if (tile_bg != nullptr) tile_bg[c] += T_final * dpix[c];
        accum[c] = T(0);
        last_color[c] = T(0);
      }
      T transmittance = T_final;
      T last_alpha = T(0);
      for (int idx = start + n_contrib[pix] - 1; idx >= start; --idx) {
        const int g = bins.point_list[idx];
        const T dx = mean[2 * g] - px;
        const T dy = mean[2 * g + 1] - py;
        const T* q = conic + 3 * g;
        const T power = T(-0.5) * (q[0] * dx * dx + q[2] * dy * dy) - q[1] * dx * dy;
        if (power > T(0)) continue;
        const T G = std::exp(power);
        const T alpha = std::min(T(kMaxAlpha), opacity[g] * G);
        if (alpha < T(kMinAlpha)) continue;
        transmittance = transmittance / (T(1) - alpha);
        const T dchannel_dcolor = alpha * transmittance;
        const T* f = features + static_cast<std::size_t>(g) * channels;
        if (weights != nullptr) {
          const T share = share_image != nullptr
                              ? dchannel_dcolor * ShareScale(f, share_image + pix * channels)
                              : dchannel_dcolor;
          weights[idx] = std::max(weights[idx], share);
        }
        T* slot = slots + static_cast<std::size_t>(idx) * stride;
        T dL_dalpha = T(0);
        for (int c = 0; c < channels; ++c) {
          accum[c] = last_alpha * last_color[c] + (T(1) - last_alpha) * accum[c];
          last_color[c] = f[c];
          dL_dalpha += (f[c] - accum[c]) * gpix[c];
          slot[detail::kSlotFeatures + c] += dchannel_dcolor * dpix[c];
        }
        dL_dalpha *= transmittance;
        last_alpha = alpha;
        dL_dalpha += (-T_final / (T(1) - alpha)) * dL_dT_final;
        AddGeometrySlots(opacity[g], G, dx, dy, q, dL_dalpha, slot);
      }
    }
  }
}

template <typename T>
void PrepareGradients(std::size_t n, int channels, SplatGradientsT<T>* grads) {
  HDR4D_CHECK(grads != nullptr);
  const auto prepare = [](std::vector<T>& v, std::size_t size) {
    if (v.empty()) v.assign(size, T(0));
    HDR4D_CHECK(v.size() == size);
  };
  prepare(grads->mean2d, 2 * n);
  prepare(grads->conic, 3 * n);
  prepare(grads->opacity, n);
  prepare(grads->features, n * static_cast<std::size_t>(channels));
  HDR4D_CHECK(grads->max_weight.empty() || grads->max_weight.size() == n);
}

// Raises `largest` to the blending weights of entries k0..k1 (indexed like the slots).
template <typename T>
void MaxIntoWeight(const RasterState& bins, const T* weights, int k0, int k1, bool streamed,
                   T* largest) {
  T m = *largest;
  for (int k = k0; k < k1; ++k) m = std::max(m, weights[streamed ? k : bins.point_entries[k]]);
  *largest = m;
}

// dL/dbackground += the per-tile partials, summed in tile order.
template <typename T>
void AddTileBackgrounds(const RasterState& bins, int channels, const T* tile_bg,
                        T* dL_dbackground) {
  for (int c = 0; c < channels; ++c) {
    T sum = T(0);
    for (int t = 0; t < bins.num_tiles(); ++t)
      sum += tile_bg[static_cast<std::size_t>(t) * channels + c];
    dL_dbackground[c] += sum;
  }
}

// Sums every listed Gaussian's entry slots in ascending tile order into `grads` (+=), and the
// per-tile background partials in tile order into dL_dbackground (+=). The slots are indexed by
// point_list entry, or, when `streamed`, already in per-Gaussian order (RasterState::entry_slots):
// the same values summed in the same order, read contiguously. `weights` (nullable, indexed like
// the slots): each entry's largest blending weight, maxed into grads->max_weight.
template <typename T>
void ReduceGradients(const RasterState& bins,
                     int channels,
                     const T* slots,
                     const T* tile_bg,
                     SplatGradientsT<T>* grads,
                     T* dL_dbackground,
                     const T* weights,
                     bool streamed = false) {
  const int stride = SlotStride(channels);
  const std::int64_t visible = static_cast<std::int64_t>(bins.depth_order.size());
  // The slots are read in an order unrelated to their layout (tile-major): prefetch the slots of
  // the Gaussian kAhead places on, and let a compile-time stride unroll the common case. The
  // gradient rows are updated in depth order, i.e. at random: prefetch those of the Gaussian
  // kAhead places on too (without it, the load of mean2d's row was 40% of this loop's time in
  // a real 200x200 run).
  const auto reduce = [&]<int kStride>(std::int64_t begin, std::int64_t end) {
    const int n = kStride > 0 ? kStride : stride;
    constexpr int kAhead = 6;
    const std::int64_t visible_end = visible;
    // With a compile-time stride the sums are a local array the compiler keeps in registers
    // (in a buffer behind a pointer, each add reloaded a sum just stored, stalling on the store).
    const auto run = [&](auto& sum) {
      for (std::int64_t i = begin; i < end; ++i) {
        if (!streamed && i + kAhead < visible_end) {
          for (int k = bins.entry_ranges[i + kAhead]; k < bins.entry_ranges[i + kAhead + 1]; ++k) {
            const T* ahead = slots + static_cast<std::size_t>(bins.point_entries[k]) * n;
            __builtin_prefetch(ahead);
            __builtin_prefetch(ahead + n - 1);
          }
        }
        if (i + kAhead < visible_end) {
          const std::int64_t ahead = bins.depth_order[i + kAhead];
          __builtin_prefetch(&grads->mean2d[2 * ahead], 1);
          __builtin_prefetch(&grads->conic[3 * ahead], 1);
          __builtin_prefetch(&grads->opacity[ahead], 1);
          __builtin_prefetch(&grads->features[ahead * channels], 1);
        }
        const std::int64_t g = bins.depth_order[i];
        const int k0 = bins.entry_ranges[i];
        const int k1 = bins.entry_ranges[i + 1];
        for (int s = 0; s < n; ++s) sum[s] = T(0);
        for (int k = k0; k < k1; ++k) {
          const std::size_t at = streamed ? static_cast<std::size_t>(k) : bins.point_entries[k];
          const T* slot = slots + at * n;
          for (int s = 0; s < n; ++s) sum[s] += slot[s];
        }
        grads->mean2d[2 * g] += sum[detail::kSlotMean];
        grads->mean2d[2 * g + 1] += sum[detail::kSlotMean + 1];
        for (int i = 0; i < 3; ++i) grads->conic[3 * g + i] += sum[detail::kSlotConic + i];
        grads->opacity[g] += sum[detail::kSlotOpacity];
        T* gf = grads->features.data() + g * channels;
        for (int c = 0; c < channels; ++c) gf[c] += sum[detail::kSlotFeatures + c];
        if (weights != nullptr)
          MaxIntoWeight(bins, weights, k0, k1, streamed, &grads->max_weight[g]);
      }
    };
    if constexpr (kStride > 0) {
      std::array<T, kStride> sum;
      run(sum);
    } else {
      SmallBuffer<T> sum(n);
      run(sum);
    }
  };
  ParallelForChunks(visible, 2048, [&](std::int64_t begin, std::int64_t end) {
    switch (stride) {
      case detail::kSlotFeatures + 3:
        return reduce.template operator()<detail::kSlotFeatures + 3>(begin, end);
      case detail::kSlotFeatures + 6:
        return reduce.template operator()<detail::kSlotFeatures + 6>(begin, end);
      default:
        return reduce.template operator()<0>(begin, end);
    }
  });
  if (dL_dbackground != nullptr) AddTileBackgrounds(bins, channels, tile_bg, dL_dbackground);
}

template <typename T>
void BackwardReferenceWithScratch(const SplatBuffersT<T>& splats,
                                  const RasterState& bins,
                                  const T* background,
                                  const T* final_T,
                                  const std::int32_t* n_contrib,
                                  const T* dL_dimage,
                                  const T* dL_dgeometry,
                                  const T* dL_dfinal_T,
                                  SplatGradientsT<T>* grads,
                                  T* dL_dbackground,
                                  const T* share_image,
                                  std::vector<T>& slots,
                                  std::vector<T>& tile_bg) {
  const int channels = splats.channels;
  HDR4D_CHECK(share_image == nullptr || channels >= kShareChannels);
  slots.resize(bins.num_entries() * SlotStride(channels));
  tile_bg.resize(static_cast<std::size_t>(bins.num_tiles()) * channels);
  T* bg_partials = dL_dbackground != nullptr ? tile_bg.data() : nullptr;
  std::vector<T> weights;
  if (!grads->max_weight.empty()) weights.resize(bins.num_entries());
  T* entry_weights = weights.empty() ? nullptr : weights.data();
  ParallelFor(bins.num_tiles(), 1, [&](std::int64_t tile) {
    BackwardTileReference(splats, bins, background, final_T, n_contrib, dL_dimage,
                          dL_dgeometry != nullptr ? dL_dgeometry : dL_dimage, dL_dfinal_T,
                          entry_weights != nullptr ? share_image : nullptr, slots.data(),
                          bg_partials ? bg_partials + tile * channels : nullptr,
                          entry_weights, static_cast<int>(tile));
  });
  ReduceGradients(bins, channels, slots.data(), bg_partials, grads, dL_dbackground,
                  static_cast<const T*>(entry_weights));
}

// The settings' background, or zeros, without allocating in a steady state.
const float* BackgroundOf(const RasterSettings& settings, int channels) {
  if (!settings.background.empty()) {
    HDR4D_CHECK(static_cast<int>(settings.background.size()) == channels);
    return settings.background.data();
  }
  thread_local std::vector<float> zeros;
  zeros.assign(channels, 0.0f);
  return zeros.data();
}

detail::TileJob MakeJob(const SplatBuffers& splats,
                          const RasterSettings& settings,
                          RasterState* state) {
  detail::TileJob job;
  job.mean2d = splats.mean2d.data();
  job.conic = splats.conic.data();
  job.opacity = splats.opacity.data();
  job.features = splats.features.data();
  job.channels = splats.channels;
  job.background = BackgroundOf(settings, splats.channels);
  job.tile_ranges = state->tile_ranges.data();
  job.point_list = state->point_list.data();
  job.width = state->width;
  job.height = state->height;
  job.tiles_x = state->tiles_x;
  job.final_T = state->final_transmittance.data();
  job.n_contrib = state->n_contrib.data();
  job.rects = state->rects.data();
  return job;
}

// packed_splats holds the per-Gaussian records, then the forward's per-entry records, then a
// marker that is 1 once the forward has written the latter for the current packing.
// With_records false (a forward no backward follows): no room for the per-entry records, and
// job.tile_records null so the forward gathers into its scratch. PackedSize is its length for
// `entries` list entries.
std::size_t PackedSize(int channels, int gaussians, std::size_t entries, bool with_records) {
  return static_cast<std::size_t>(gaussians) * detail::PackedStride(channels) +
         (with_records ? entries * detail::TileRecordStride(channels) : 0) + 1;
}

// Points `job` at the packed records (which must be laid out for `entries` list entries).
void UsePacked(detail::TileJob& job, RasterState* state, std::size_t entries, bool with_records) {
  HDR4D_CHECK(state->packed_splats.size() ==
              PackedSize(job.channels, state->num_gaussians, entries, with_records));
  job.packed = state->packed_splats.data();
  job.tile_records =
      with_records ? job.packed + static_cast<std::size_t>(state->num_gaussians) *
                                      detail::PackedStride(job.channels)
                   : nullptr;
}

// The SIMD kernels' per-Gaussian records, for the Gaussians listed in some tile (in parallel,
// in id order). They need the splats and the tile rectangles only, so they can be packed beside
// the depth sort (RasterizeForward); `entries` is the number of list entries the binning makes.
void PackSplats(detail::TileJob& job, RasterState* state, std::size_t entries, bool with_records) {
  ResizeScratch(&state->packed_splats,
                PackedSize(job.channels, state->num_gaussians, entries, with_records));
  state->packed_splats.back() = 0.0f;
  UsePacked(job, state, entries, with_records);
  ParallelForChunks(
      static_cast<std::int64_t>(state->num_gaussians), 4096,
      [&](std::int64_t begin, std::int64_t end) { detail::PackSplatsSimd(job, begin, end); });
  state->packed_ready = true;
}

// The records of this binning for `job`: packed already (beside the depth sort,
// RasterizeForward) or packed now.
void EnsurePacked(detail::TileJob& job, RasterState* state, bool with_records) {
  if (state->packed_ready) {
    UsePacked(job, state, state->num_entries(), with_records);
  } else {
    PackSplats(job, state, state->num_entries(), with_records);
  }
}

void CheckCall(const SplatBuffers& splats, const RasterSettings& settings, const RasterState& s) {
  HDR4D_CHECK(splats.Validate().empty());
  HDR4D_CHECK(s.width == settings.width && s.height == settings.height);
  CheckBinned(s, splats.size());
}

}  // namespace

template <typename T>
void BlendForwardReference(const SplatBuffersT<T>& splats,
                           const RasterState& bins,
                           const T* background,
                           T* image,
                           T* final_T,
                           std::int32_t* n_contrib) {
  HDR4D_CHECK(splats.Validate().empty());
  CheckBinned(bins, splats.size());
  HDR4D_CHECK(image != nullptr && final_T != nullptr && n_contrib != nullptr);
  std::vector<T> zeros;
  if (background == nullptr) {
    zeros.assign(splats.channels, T(0));
    background = zeros.data();
  }
  ParallelFor(bins.num_tiles(), 1, [&](std::int64_t tile) {
    ForwardTileReference(splats, bins, background, image, final_T, n_contrib,
                         static_cast<int>(tile));
  });
}

template <typename T>
void BlendBackwardReference(const SplatBuffersT<T>& splats,
                            const RasterState& bins,
                            const T* background,
                            const T* final_T,
                            const std::int32_t* n_contrib,
                            const T* dL_dimage,
                            const T* dL_dfinal_T,
                            SplatGradientsT<T>* grads,
                            T* dL_dbackground,
                            const T* dL_dimage_geometry,
                            const T* share_image) {
  HDR4D_CHECK(splats.Validate().empty());
  CheckBinnedForBackward(bins, splats.size());
  HDR4D_CHECK(final_T != nullptr && n_contrib != nullptr && dL_dimage != nullptr);
  PrepareGradients(splats.size(), splats.channels, grads);
  std::vector<T> zeros;
  if (background == nullptr) {
    zeros.assign(splats.channels, T(0));
    background = zeros.data();
  }
  std::vector<T> slots;
  std::vector<T> tile_bg;
  BackwardReferenceWithScratch(splats, bins, background, final_T, n_contrib, dL_dimage,
                               dL_dimage_geometry, dL_dfinal_T, grads, dL_dbackground,
                               share_image, slots, tile_bg);
}

void BlendForward(const SplatBuffers& splats,
                  const RasterSettings& settings,
                  RasterState* state,
                  float* image) {
  HDR4D_CHECK(state != nullptr && image != nullptr);
  CheckCall(splats, settings, *state);
  const std::size_t pixels = static_cast<std::size_t>(state->width) * state->height;
  state->final_transmittance.resize(pixels);
  // n_contrib is only for a backward: a forward without keep_records leaves it empty (the SIMD
  // kernel then does not track it).
  if (settings.backend == RasterBackend::kScalar) {
    state->n_contrib.resize(pixels);
    state->packed_ready = false;  // a later kSimd backward must pack these splats
    BlendForwardReference<float>(splats, *state, BackgroundOf(settings, splats.channels), image,
                                 state->final_transmittance.data(), state->n_contrib.data());
    if (!settings.keep_records) state->n_contrib.clear();
    return;
  }
  if (settings.keep_records) {
    state->n_contrib.resize(pixels);
  } else {
    state->n_contrib.clear();
  }
  detail::TileJob job = MakeJob(splats, settings, state);
  job.image = image;
  EnsurePacked(job, state, settings.keep_records);
  ParallelFor(state->num_tiles(), 1,
              [&](std::int64_t tile) { detail::ForwardTileSimd(job, static_cast<int>(tile)); });
  // The per-entry records are there for the backward (else it gathers its own).
  if (settings.keep_records) state->packed_splats.back() = 1.0f;
}

// The SIMD kernels' records are packed beside the depth sort: on two threads the sort of a 200 x
// 200 training view's 20k Gaussians is serial and would leave the other thread idle.
void RasterizeForward(const SplatBuffers& splats,
                      const RasterSettings& settings,
                      RasterState* state,
                      float* image) {
  if (settings.backend == RasterBackend::kSimd) {
    BinSplats(splats, settings, state, [&](std::int64_t entries) {
      detail::TileJob job = MakeJob(splats, settings, state);
      PackSplats(job, state, static_cast<std::size_t>(entries), settings.keep_records);
    });
  } else {
    BinSplats(splats, settings, state);
  }
  BlendForward(splats, settings, state, image);
}

void BlendBackward(const SplatBuffers& splats,
                   const RasterSettings& settings,
                   RasterState* state,
                   const float* dL_dimage,
                   const float* dL_dfinal_T,
                   SplatGradients* grads,
                   float* dL_dbackground,
                   const float* dL_dimage_geometry) {
  HDR4D_CHECK(state != nullptr && dL_dimage != nullptr);
  CheckCall(splats, settings, *state);
  CheckBinnedForBackward(*state, splats.size());
  const std::size_t pixels = static_cast<std::size_t>(state->width) * state->height;
  HDR4D_CHECK(state->final_transmittance.size() == pixels && state->n_contrib.size() == pixels);
  PrepareGradients(splats.size(), splats.channels, grads);
  const float* background = BackgroundOf(settings, splats.channels);
  if (settings.backend == RasterBackend::kScalar) {
    BackwardReferenceWithScratch<float>(splats, *state, background,
                                        state->final_transmittance.data(), state->n_contrib.data(),
                                        dL_dimage, dL_dimage_geometry, dL_dfinal_T, grads,
                                        dL_dbackground, settings.share_image,
                                        state->entry_gradients, state->tile_background_grad);
    return;
  }
  const int channels = splats.channels;
  ResizeScratch(&state->entry_gradients, state->num_entries() * SlotStride(channels));
  state->tile_background_grad.resize(static_cast<std::size_t>(state->num_tiles()) * channels);
  detail::TileJob job = MakeJob(splats, settings, state);
  job.dL_dimage = dL_dimage;
  job.dL_dfinal_T = dL_dfinal_T;
  job.dL_dimage_geometry = dL_dimage_geometry;
  job.entry_gradients = state->entry_gradients.data();
  job.entry_slots = state->entry_slots.data();
  job.tile_background_grad =
      dL_dbackground != nullptr ? state->tile_background_grad.data() : nullptr;
  if (!grads->max_weight.empty()) {
    ResizeScratch(&state->entry_max_weight, state->num_entries());
    job.entry_max_weight = state->entry_max_weight.data();
    job.share_image = settings.share_image;
    HDR4D_CHECK(job.share_image == nullptr || channels >= kShareChannels);
  }
  EnsurePacked(job, state, /*with_records=*/true);
  job.tile_records_ready = state->packed_splats.back() == 1.0f;
  ParallelFor(state->num_tiles(), 1,
              [&](std::int64_t tile) { detail::BackwardTileSimd(job, static_cast<int>(tile)); });
  ReduceGradients<float>(*state, channels, state->entry_gradients.data(), job.tile_background_grad,
                         grads, dL_dbackground, job.entry_max_weight, /*streamed=*/true);
}

template void BlendForwardReference<float>(
    const SplatBuffersT<float>&, const RasterState&, const float*, float*, float*, std::int32_t*);
template void BlendForwardReference<double>(const SplatBuffersT<double>&,
                                            const RasterState&,
                                            const double*,
                                            double*,
                                            double*,
                                            std::int32_t*);
template void BlendBackwardReference<float>(const SplatBuffersT<float>&,
                                            const RasterState&,
                                            const float*,
                                            const float*,
                                            const std::int32_t*,
                                            const float*,
                                            const float*,
                                            SplatGradientsT<float>*,
                                            float*,
                                            const float*,
                                            const float*);
template void BlendBackwardReference<double>(const SplatBuffersT<double>&,
                                             const RasterState&,
                                             const double*,
                                             const double*,
                                             const std::int32_t*,
                                             const double*,
                                             const double*,
                                             SplatGradientsT<double>*,
                                             double*,
                                             const double*,
                                             const double*);

}  // namespace hdr4d::method
