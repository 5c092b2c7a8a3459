#include "method/train/loss_plateau.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace hdr4d::method {
namespace {

// A loss falling as 1 / (1 + i / scale): its relative gain per window shrinks over the run.
std::vector<double> FallingLoss(int n, double scale) {
  std::vector<double> loss(n);
  for (int i = 0; i < n; ++i) loss[i] = 1.0 / (1.0 + i / scale);
  return loss;
}

TEST(LossPlateau, WindowZeroNeverStops) {
  EXPECT_FALSE(FindLossPlateau(std::vector<double>(4000, 0.1), 0, 0, 0.5).has_value());
}

TEST(LossPlateau, FlatLossStopsAtTheFirstWindowBoundaryAfterDensification) {
  const std::vector<double> flat(3000, 0.1);
  // Both windows must lie after densify_until: 1000 + 2 x 500 = 2000.
  for (int n = 1; n <= 3000; ++n) {
    const std::vector<double> curve(flat.begin(), flat.begin() + n);
    const auto p = FindLossPlateau(curve, 1000, 500, 0.002);
    EXPECT_EQ(p.has_value(), n % 500 == 0 && n >= 2000) << n;
    if (p) {
      EXPECT_EQ(p->iteration, n);
      EXPECT_DOUBLE_EQ(p->improvement, 0.0);
    }
  }
}

TEST(LossPlateau, StopsOnlyOnceTheGainPerWindowFallsBelowTheTolerance) {
  const std::vector<double> loss = FallingLoss(200000, 100.0);
  int stop = 0;
  for (int n = 100; n <= 200000 && stop == 0; n += 100) {
    const std::vector<double> curve(loss.begin(), loss.begin() + n);
    if (auto p = FindLossPlateau(curve, 0, 100, 0.01)) {
      stop = p->iteration;
      EXPECT_LT(p->improvement, 0.01);
      EXPECT_GT(p->previous, p->last);
    }
  }
  // Relative gain of a window of 100 at iteration n is about 100 / (n + 100): under 1% past
  // about 10000 iterations; and the window before must not have stopped.
  EXPECT_GT(stop, 9000);
  EXPECT_LT(stop, 11000);
  const std::vector<double> before(loss.begin(), loss.begin() + stop - 100);
  EXPECT_FALSE(FindLossPlateau(before, 0, 100, 0.01).has_value());
}

TEST(LossPlateau, RisingLossStopsAndZeroLossIsGuarded) {
  std::vector<double> rising(400);
  for (int i = 0; i < 400; ++i) rising[i] = 0.1 + 1e-4 * i;
  EXPECT_TRUE(FindLossPlateau(rising, 0, 200, 0.0).has_value());
  const auto zero = FindLossPlateau(std::vector<double>(400, 0.0), 0, 200, 1e-3);
  ASSERT_TRUE(zero.has_value());  // nothing left to improve: 0 gain, not a division by zero
  EXPECT_EQ(zero->improvement, 0.0);
  EXPECT_TRUE(std::isfinite(zero->improvement));
}

TEST(LossPlateau, ImprovingLossDoesNotStop) {
  std::vector<double> falling(400);
  for (int i = 0; i < 400; ++i) falling[i] = 1.0 - 1e-3 * i;  // 20% better per window
  EXPECT_FALSE(FindLossPlateau(falling, 0, 200, 0.002).has_value());
}

}  // namespace
}  // namespace hdr4d::method
