#include "method/raster/binning.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/util/parallel.h"
#include "method/gaussian/constants.h"

namespace hdr4d::method {
namespace {

RasterSettings Size(int width, int height) {
  RasterSettings s;
  s.width = width;
  s.height = height;
  return s;
}

// Random visible splats (the blend-relevant fields are irrelevant to binning).
SplatBuffers RandomSplats(int n, int width, int height, unsigned seed, int max_radius = 30) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  SplatBuffers s;
  s.channels = 1;
  s.Resize(n);
  for (int g = 0; g < n; ++g) {
    s.mean2d[2 * g] = -20.0f + (width + 40.0f) * u(rng);
    s.mean2d[2 * g + 1] = -20.0f + (height + 40.0f) * u(rng);
    s.radius[g] = static_cast<int>(u(rng) * max_radius);  // some 0: culled
    // Coarse depths so that ties occur.
    s.depth[g] = 0.5f + std::floor(u(rng) * 50.0f) * 0.1f;
    s.opacity[g] = 0.5f;
    s.conic[3 * g] = s.conic[3 * g + 2] = 1.0f;
  }
  return s;
}

// Brute force: Gaussian g is in tile (tx, ty) iff the open interval (m - r, m + r) meets the
// tile's span [16 t, 16 t + 16) on both axes; r per axis from `reach` when the splats have it.
bool Overlaps(const SplatBuffers& s, int g, int tx, int ty) {
  if (s.radius[g] <= 0) return false;
  const bool snug = !s.reach.empty();
  const double rx = snug ? s.reach[2 * g] : s.radius[g];
  const double ry = snug ? s.reach[2 * g + 1] : s.radius[g];
  if (rx <= 0 || ry <= 0) return false;  // reaches no pixel on one axis
  const double mx = s.mean2d[2 * g], my = s.mean2d[2 * g + 1];
  const auto meets = [&](double m, double r, int t) {
    return kTileSize * t < m + r && kTileSize * (t + 1) > m - r;
  };
  return meets(mx, rx, tx) && meets(my, ry, ty);
}

// Per-axis reaches of at most the radius, some 0 (reaching no pixel), some the radius.
void AddRandomReach(SplatBuffers* s, unsigned seed) {
  std::mt19937 rng(seed);
  s->reach.resize(2 * s->size());
  for (std::size_t g = 0; g < s->size(); ++g) {
    for (int k = 0; k < 2; ++k) {
      std::uniform_int_distribution<int> u(s->radius[g] > 5 ? -1 : 0, s->radius[g]);
      s->reach[2 * g + k] = std::max(0, u(rng));
    }
  }
}

// Every structural invariant of a binning against brute force.
void ExpectConsistent(const SplatBuffers& s, const RasterState& b) {
  const int n = static_cast<int>(s.size());
  ASSERT_EQ(b.tiles_x, TileCount(b.width));
  ASSERT_EQ(b.tiles_y, TileCount(b.height));
  ASSERT_EQ(static_cast<int>(b.tile_ranges.size()), b.num_tiles() + 1);
  ASSERT_EQ(b.tile_ranges.front(), 0);
  ASSERT_EQ(static_cast<std::size_t>(b.tile_ranges.back()), b.point_list.size());
  ASSERT_EQ(b.entry_ranges.size(), b.depth_order.size() + 1);
  ASSERT_EQ(b.point_entries.size(), b.point_list.size());
  for (int ty = 0; ty < b.tiles_y; ++ty) {
    for (int tx = 0; tx < b.tiles_x; ++tx) {
      const int t = ty * b.tiles_x + tx;
      std::vector<int> listed(b.point_list.begin() + b.tile_ranges[t],
                              b.point_list.begin() + b.tile_ranges[t + 1]);
      // Sorted by depth, ties by id.
      for (std::size_t i = 1; i < listed.size(); ++i) {
        const int p = listed[i - 1], q = listed[i];
        ASSERT_TRUE(s.depth[p] < s.depth[q] || (s.depth[p] == s.depth[q] && p < q))
            << "tile " << t << " position " << i;
      }
      std::vector<int> expected;
      for (int g = 0; g < n; ++g)
        if (Overlaps(s, g, tx, ty)) expected.push_back(g);
      std::sort(listed.begin(), listed.end());
      ASSERT_EQ(listed, expected) << "tile " << tx << "," << ty;
    }
  }
  // depth_order lists exactly the Gaussians with entries, front to back (ties by id).
  std::vector<int> listed;
  for (int g = 0; g < n; ++g) {
    bool any = false;
    for (int t = 0; t < b.num_tiles(); ++t)
      any = any || Overlaps(s, g, t % b.tiles_x, t / b.tiles_x);
    if (any) listed.push_back(g);
  }
  std::vector<int> order(b.depth_order.begin(), b.depth_order.end());
  for (std::size_t i = 1; i < order.size(); ++i) {
    const int p = order[i - 1], q = order[i];
    ASSERT_TRUE(s.depth[p] < s.depth[q] || (s.depth[p] == s.depth[q] && p < q));
  }
  std::sort(order.begin(), order.end());
  ASSERT_EQ(order, listed);
  ASSERT_EQ(static_cast<std::size_t>(b.entry_ranges.back()), b.point_list.size());
  // Each Gaussian's entries point back at it, in ascending tile order, and cover all of them.
  std::vector<int> seen(b.point_list.size(), 0);
  for (std::size_t i = 0; i < b.depth_order.size(); ++i) {
    const int g = b.depth_order[i];
    int previous_tile = -1;
    for (int k = b.entry_ranges[i]; k < b.entry_ranges[i + 1]; ++k) {
      const int entry = b.point_entries[k];
      ASSERT_EQ(b.point_list[entry], g);
      const int tile =
          static_cast<int>(std::upper_bound(b.tile_ranges.begin(), b.tile_ranges.end(), entry) -
                           b.tile_ranges.begin() - 1);
      ASSERT_GT(tile, previous_tile);
      previous_tile = tile;
      ++seen[entry];
    }
  }
  for (int count : seen) ASSERT_EQ(count, 1);
}

TEST(RasterBinning, MatchesBruteForceWithPartialTiles) {
  // 40 x 37: 3 x 3 tiles, the last column 8 pixels wide and the last row 5 high.
  for (unsigned seed : {1u, 2u, 3u}) {
    const SplatBuffers s = RandomSplats(300, 40, 37, seed);
    RasterState b;
    BinSplats(s, Size(40, 37), &b);
    EXPECT_EQ(b.tiles_x, 3);
    EXPECT_EQ(b.tiles_y, 3);
    EXPECT_GT(b.num_entries(), 300u);
    ExpectConsistent(s, b);
  }
  const SplatBuffers s = RandomSplats(2000, 200, 130, 9, 50);
  RasterState b;
  BinSplats(s, Size(200, 130), &b);
  ExpectConsistent(s, b);
}

TEST(RasterBinning, PerAxisReachListsTheTilesOfItsRectangle) {
  for (unsigned seed : {4u, 5u}) {
    SplatBuffers s = RandomSplats(2000, 200, 130, seed, 50);
    RasterState square;
    BinSplats(s, Size(200, 130), &square);
    AddRandomReach(&s, seed);
    RasterState snug;
    BinSplats(s, Size(200, 130), &snug);
    ExpectConsistent(s, snug);
    EXPECT_LT(snug.num_entries(), square.num_entries() * 9 / 10);
  }
  // The rectangle takes each axis's radius.
  const TileRect wide = GaussianTileRect(40.0f, 40.0f, 20, 3, 8, 8);
  EXPECT_EQ(wide.x0, 1);
  EXPECT_EQ(wide.x1, 4);
  EXPECT_EQ(wide.y0, 2);
  EXPECT_EQ(wide.y1, 3);
  EXPECT_TRUE(GaussianTileRect(40.0f, 40.0f, 20, 0, 8, 8).empty());
}

TEST(RasterBinning, TileRectangleRule) {
  // Corner-origin coordinates: tile k spans [16k, 16k + 16).
  EXPECT_EQ(GaussianTileRect(8.0f, 8.0f, 3, 4, 4).x0, 0);
  EXPECT_EQ(GaussianTileRect(8.0f, 8.0f, 3, 4, 4).x1, 1);
  // m + r exactly on a boundary: the next tile's first pixel centre (16.5) is outside.
  EXPECT_EQ(GaussianTileRect(10.0f, 8.0f, 6, 4, 4).x1, 1);
  EXPECT_EQ(GaussianTileRect(10.25f, 8.0f, 6, 4, 4).x1, 2);
  // m - r exactly on a boundary: tile 0 (last centre 15.5) is outside.
  EXPECT_EQ(GaussianTileRect(22.0f, 8.0f, 6, 4, 4).x0, 1);
  EXPECT_EQ(GaussianTileRect(21.75f, 8.0f, 6, 4, 4).x0, 0);
  // Clipping at the image borders.
  const TileRect left = GaussianTileRect(-3.0f, 5.0f, 10, 3, 3);
  EXPECT_EQ(left.x0, 0);
  EXPECT_EQ(left.x1, 1);
  EXPECT_EQ(left.y0, 0);
  EXPECT_EQ(left.y1, 1);
  const TileRect corner = GaussianTileRect(43.0f, 40.0f, 5, 3, 3);  // 40 x 37 image
  EXPECT_EQ(corner.x0, 2);
  EXPECT_EQ(corner.x1, 3);
  EXPECT_EQ(corner.y0, 2);
  EXPECT_EQ(corner.y1, 3);
  const TileRect huge = GaussianTileRect(20.0f, 20.0f, 1000, 3, 3);
  EXPECT_EQ(huge.area(), 9);
  // Outside the image, culled, non-finite or far away: nothing.
  EXPECT_TRUE(GaussianTileRect(-20.0f, 5.0f, 5, 3, 3).empty());
  EXPECT_TRUE(GaussianTileRect(60.0f, 5.0f, 5, 3, 3).empty());
  EXPECT_TRUE(GaussianTileRect(20.0f, 20.0f, 0, 3, 3).empty());
  EXPECT_TRUE(GaussianTileRect(std::numeric_limits<float>::quiet_NaN(), 5.0f, 5, 3, 3).empty());
  EXPECT_TRUE(GaussianTileRect(std::numeric_limits<float>::infinity(), 5.0f, 5, 3, 3).empty());
  EXPECT_TRUE(GaussianTileRect(3e30f, 5.0f, 5, 3, 3).empty());
  EXPECT_EQ(GaussianTileRect(-3e30, 5.0, 5, 3, 3).area(), 0);
  EXPECT_EQ(TileCount(16), 1);
  EXPECT_EQ(TileCount(17), 2);
  EXPECT_EQ(TileCount(800), 50);
}

TEST(RasterBinning, CulledAndOffscreenGaussiansCostNoEntries) {
  SplatBuffers s = RandomSplats(4, 64, 64, 1);
  s.mean2d = {30, 30, 30, 30, -100, 30, 30, std::numeric_limits<float>::quiet_NaN()};
  s.radius = {1, 0, 5, 5};
  RasterState b;
  BinSplats(s, Size(64, 64), &b);
  EXPECT_EQ(b.num_entries(), 1u);
  EXPECT_EQ(b.depth_order, (std::vector<std::int32_t>{0}));
  EXPECT_EQ(b.entry_ranges, (std::vector<std::int32_t>{0, 1}));
  // The one visible Gaussian at (30, 30) r 1 covers tile (1, 1) only.
  const int t = 1 * 4 + 1;
  EXPECT_EQ(b.tile_ranges[t + 1] - b.tile_ranges[t], 1);
}

TEST(RasterBinning, DepthOrderWithTiesAndNegativeDepths) {
  SplatBuffers s;
  s.channels = 1;
  s.Resize(6);
  for (int g = 0; g < 6; ++g) {
    s.mean2d[2 * g] = 8;
    s.mean2d[2 * g + 1] = 8;
    s.radius[g] = 2;
  }
  s.depth = {3.0f, 1.0f, 3.0f, -2.0f, 1e-8f, 1.0f};
  RasterState b;
  BinSplats(s, Size(16, 16), &b);
  EXPECT_EQ(b.point_list, (std::vector<std::int32_t>{3, 4, 1, 5, 0, 2}));
}

TEST(RasterBinning, SameResultAtAnyThreadCountAndWhenReused) {
  // Enough visible Gaussians for the counting sort to split into chunks.
  const SplatBuffers s = RandomSplats(60000, 300, 200, 4, 40);
  RasterState one, two, reused;
  {
    ThreadLimit limit(1);
    BinSplats(s, Size(300, 200), &one);
  }
  {
    ThreadLimit limit(2);
    BinSplats(s, Size(300, 200), &two);
    BinSplats(RandomSplats(50, 20, 20, 5), Size(20, 20), &reused);
    BinSplats(s, Size(300, 200), &reused);
  }
  EXPECT_EQ(one.point_list, two.point_list);
  EXPECT_EQ(one.tile_ranges, two.tile_ranges);
  EXPECT_EQ(one.point_entries, two.point_entries);
  EXPECT_EQ(one.entry_ranges, two.entry_ranges);
  EXPECT_EQ(one.depth_order, two.depth_order);
  EXPECT_EQ(one.point_list, reused.point_list);
  EXPECT_EQ(one.point_entries, reused.point_entries);
  ExpectConsistent(s, two);
}

// Work given to BinSplats runs beside the depth sort: it is called once, with the number of list
// entries the binning then makes, sees the tile rectangles already written, and changes nothing
// in the binning, at one and two threads.
TEST(RasterBinning, WorkBesideTheSortSeesTheEntriesAndChangesNothing) {
  const SplatBuffers s = RandomSplats(30000, 200, 200, 4, 40);
  RasterState plain;
  BinSplats(s, Size(200, 200), &plain);
  for (const int threads : {1, 2}) {
    ThreadLimit limit(threads);
    RasterState beside;
    int calls = 0;
    std::int64_t entries = -1;
    std::vector<std::int32_t> rects_seen;
    BinSplats(s, Size(200, 200), &beside, [&](std::int64_t e) {
      ++calls;
      entries = e;
      rects_seen = beside.rects;
    });
    EXPECT_EQ(calls, 1) << threads;
    EXPECT_EQ(entries, static_cast<std::int64_t>(beside.num_entries())) << threads;
    EXPECT_GT(entries, 30000) << threads;
    EXPECT_EQ(rects_seen, plain.rects) << threads;
    EXPECT_EQ(beside.point_list, plain.point_list) << threads;
    EXPECT_EQ(beside.tile_ranges, plain.tile_ranges) << threads;
    EXPECT_EQ(beside.point_entries, plain.point_entries) << threads;
    EXPECT_EQ(beside.entry_ranges, plain.entry_ranges) << threads;
    EXPECT_EQ(beside.depth_order, plain.depth_order) << threads;
    ExpectConsistent(s, beside);
  }
}

// The radix sort is std::stable_sort by key, serial and in parallel chunks (from 65536 pairs),
// with ties, keys that differ only in the high digit (one pass skipped) and all keys equal.
TEST(RasterBinning, RadixSortIsAStableSortAtAnyThreadCount) {
  std::mt19937 rng(7);
  for (const int n : {0, 1, 5000, 65535, 65536, 200001}) {
    for (const int kind : {0, 1, 2}) {
      std::vector<std::uint32_t> keys(n);
      for (auto& k : keys) {
        const std::uint32_t r = rng();
        k = kind == 0 ? r % 1000 : kind == 1 ? (r & 0xffc00000u) | 0x155u : 42u;
      }
      std::vector<std::int32_t> ids(n);
      for (int i = 0; i < n; ++i) ids[i] = i;
      std::vector<std::int32_t> expected = ids;
      std::stable_sort(expected.begin(), expected.end(),
                       [&](std::int32_t a, std::int32_t b) { return keys[a] < keys[b]; });
      for (const int threads : {1, 2}) {
        ThreadLimit limit(threads);
        std::vector<std::uint32_t> k = keys, kt;
        std::vector<std::int32_t> id = ids, it;
        RadixSortByKey(k, id, kt, it);
        ASSERT_EQ(id, expected) << "n " << n << " kind " << kind << " threads " << threads;
        for (int i = 0; i < n; ++i) ASSERT_EQ(k[i], keys[expected[i]]);
      }
    }
  }
}

TEST(RasterBinning, DoublePrecisionAgreesWithFloat) {
  const SplatBuffers s = RandomSplats(500, 70, 50, 8);
  SplatBuffersT<double> d;
  d.channels = 1;
  d.mean2d.assign(s.mean2d.begin(), s.mean2d.end());
  d.conic.assign(s.conic.begin(), s.conic.end());
  d.opacity.assign(s.opacity.begin(), s.opacity.end());
  d.depth.assign(s.depth.begin(), s.depth.end());
  d.features.assign(s.features.begin(), s.features.end());
  d.radius = s.radius;
  RasterState bf, bd;
  BinSplats(s, Size(70, 50), &bf);
  BinSplats(d, Size(70, 50), &bd);
  EXPECT_EQ(bf.point_list, bd.point_list);
  EXPECT_EQ(bf.tile_ranges, bd.tile_ranges);
}

TEST(RasterSplats, ValidateNamesTheInconsistentBuffer) {
  SplatBuffers good = RandomSplats(3, 16, 16, 1);
  good.channels = 2;
  good.features.assign(6, 0.0f);
  EXPECT_EQ(good.Validate(), "");
  const auto broken = [&](auto&& edit) {
    SplatBuffers s = good;
    edit(s);
    return s.Validate();
  };
  EXPECT_EQ(broken([](SplatBuffers& s) { s.mean2d.pop_back(); }),
            "mean2d must hold 2 values per Gaussian");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.conic.push_back(1); }),
            "conic must hold 3 values per Gaussian");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.depth.pop_back(); }),
            "depth must hold 1 value per Gaussian");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.radius.pop_back(); }),
            "radius must hold 1 value per Gaussian");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.features.pop_back(); }),
            "features must hold `channels` values per Gaussian");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.channels = 0; }), "channels must be >= 1");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.reach.assign(5, 1); }),
            "reach must be empty or hold 2 values per Gaussian");
  EXPECT_EQ(broken([](SplatBuffers& s) { s.reach.assign(6, 1); }), "");
  // Resize keeps every buffer consistent; SetZero sizes gradients.
  SplatBuffers resized = good;
  resized.Resize(7);
  EXPECT_EQ(resized.Validate(), "");
  EXPECT_EQ(resized.features.size(), 14u);
  SplatGradients grads;
  grads.SetZero(7, 2);
  EXPECT_EQ(grads.mean2d.size(), 14u);
  EXPECT_EQ(grads.conic.size(), 21u);
  EXPECT_EQ(grads.opacity.size(), 7u);
  EXPECT_EQ(grads.features.size(), 14u);
}

TEST(RasterBinningDeathTest, MisuseIsCaught) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  SplatBuffers s = RandomSplats(3, 16, 16, 1);
  RasterState b;
  EXPECT_DEATH(BinSplats(s, Size(0, 16), &b), "check failed");
  EXPECT_DEATH(BinSplats(s, Size(16, 16), nullptr), "check failed");
  s.depth.pop_back();
  EXPECT_DEATH(BinSplats(s, Size(16, 16), &b), "check failed");
  EXPECT_EQ(s.Validate(), "depth must hold 1 value per Gaussian");
  SplatBuffers bad_channels;
  bad_channels.channels = 0;
  EXPECT_EQ(bad_channels.Validate(), "channels must be >= 1");
}

}  // namespace
}  // namespace hdr4d::method
