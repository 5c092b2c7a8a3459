#include "core/util/scratch_vector.h"

#include <gtest/gtest.h>

#include <vector>

namespace hdr4d {
namespace {

// Growth past the capacity takes new storage with headroom; within it the storage stays.
TEST(ResizeScratch, GrowsWithHeadroomAndReusesItsStorage) {
  std::vector<float> v(100, 1.0f);
  ResizeScratch(&v, 1000);
  EXPECT_EQ(v.size(), 1000u);
  EXPECT_GE(v.capacity(), 1250u);
  const float* storage = v.data();
  ResizeScratch(&v, 1200);
  EXPECT_EQ(v.size(), 1200u);
  EXPECT_EQ(v.data(), storage);
  ResizeScratch(&v, 10);
  EXPECT_EQ(v.size(), 10u);
  EXPECT_EQ(v.data(), storage);
}

}  // namespace
}  // namespace hdr4d
