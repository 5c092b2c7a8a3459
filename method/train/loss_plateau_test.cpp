#include "method/train/loss_plateau.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
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

// Held-out points from (iteration, PSNR) pairs, one evaluation per 100 iterations.
std::vector<HeldOutPoint> HeldOut(const std::vector<double>& psnr) {
  std::vector<HeldOutPoint> curve;
  for (std::size_t i = 0; i < psnr.size(); ++i)
    curve.push_back({static_cast<int>(100 * (i + 1)), psnr[i]});
  return curve;
}

// As HeldOut, each point with a count (1000, 2000, ...).
std::vector<HeldOutPoint> HeldOutWithCounts(const std::vector<double>& psnr) {
  std::vector<HeldOutPoint> curve = HeldOut(psnr);
  for (std::size_t i = 0; i < curve.size(); ++i)
    curve[i].gaussians = static_cast<std::int64_t>(1000 * (i + 1));
  return curve;
}

TEST(HeldOutPlateau, StopsPatienceEvaluationsAfterTheBest) {
  // Rises to 25 dB at iteration 300, then falls (a model overfitting its training views).
  const std::vector<double> psnr = {20, 23, 25, 24.9, 24.7, 24.6, 24.5};
  for (std::size_t n = 1; n <= psnr.size(); ++n) {
    const std::vector<double> part(psnr.begin(), psnr.begin() + n);
    const auto p = FindHeldOutPlateau(HeldOut(part), 0.002, 3);
    EXPECT_EQ(p.has_value(), n == 6 || n == 7) << n;  // 3 evaluations after the best (n = 3)
    if (p) {
      EXPECT_EQ(p->best_iteration, 300);
      EXPECT_DOUBLE_EQ(p->best_psnr, 25);
      EXPECT_EQ(p->iteration, static_cast<int>(100 * n));
      EXPECT_DOUBLE_EQ(p->last_psnr, psnr[n - 1]);
    }
  }
}

// The best so far, which the trainer keeps to take back at the end: the last evaluation that
// improved by the tolerance, not the highest reading.
TEST(HeldOutPlateau, BestIsTheLastEvaluationThatImprovedByTheTolerance) {
  EXPECT_FALSE(BestHeldOutIndex({}, 0.002).has_value());
  EXPECT_EQ(BestHeldOutIndex(HeldOut({20}), 0.002), 0u);
  EXPECT_EQ(BestHeldOutIndex(HeldOut({20, 23, 25, 24.9, 24.7}), 0.002), 2u);
  // 25.001 dB is 0.02% lower error than 25: below a 0.2% tolerance, so 25 stays the best.
  EXPECT_EQ(BestHeldOutIndex(HeldOut({20, 25, 25.001}), 0.002), 1u);
  EXPECT_EQ(BestHeldOutIndex(HeldOut({20, 25, 25.001}), 0.0), 2u);
  EXPECT_EQ(BestHeldOutIndex(HeldOut({std::nan(""), 18}), 0.002), 1u);
}

TEST(HeldOutPlateau, SlowGainsAddUpAgainstTheBestSoFar) {
  // +0.005 dB per evaluation (0.115% lower error): measured against the best so far, two steps
  // pass a 0.2% tolerance, so the run goes on; five are needed to pass 0.5%, so the best moves
  // to the sixth evaluation (600) and four later ones do not beat it.
  std::vector<double> psnr;
  for (int i = 0; i < 10; ++i) psnr.push_back(24.0 + 0.005 * i);
  EXPECT_FALSE(FindHeldOutPlateau(HeldOut(psnr), 0.002, 3).has_value());
  const auto p = FindHeldOutPlateau(HeldOut(psnr), 0.005, 3);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->best_iteration, 600);
  EXPECT_EQ(p->iteration, 1000);
}

TEST(HeldOutPlateau, ADipFromAnOpacityResetRecoveredWithinPatienceDoesNotStop) {
  const std::vector<double> psnr = {22, 24, 14, 23.5, 24.5};  // reset at the third evaluation
  EXPECT_FALSE(FindHeldOutPlateau(HeldOut(psnr), 0.002, 3).has_value());
}

TEST(HeldOutPlateau, NonFinitePsnrNeverImprovesAndTooFewPointsNeverStop) {
  const double nan = std::nan("");
  EXPECT_FALSE(FindHeldOutPlateau(HeldOut({20, 21, 22}), 0.002, 3).has_value());
  const auto p = FindHeldOutPlateau(HeldOut({20, nan, nan, nan}), 0.002, 3);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->best_iteration, 100);
  // A first point that could not be scored is beaten by any finite one.
  const auto q = FindHeldOutPlateau(HeldOut({nan, 18, 17, 16, 15}), 0.002, 3);
  ASSERT_TRUE(q.has_value());
  EXPECT_EQ(q->best_iteration, 200);
  EXPECT_FALSE(FindHeldOutPlateau(HeldOut({20, 20, 20, 20}), 0.002, 0).has_value());
}

// --grow-on-val: the first evaluation before densify_until that does not improve on the best
// before it freezes the count at that evaluation's; later ones (better or not) do not move it.
TEST(GrowthStop, FirstEvaluationWithoutGainWhileDensifyingFreezesItsCount) {
  const std::vector<HeldOutPoint> curve = HeldOutWithCounts({20, 22, 21.9, 23, 22.5});
  const auto g = FindGrowthStop(curve, 1000, 0.002);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->iteration, 300);
  EXPECT_EQ(g->gaussians, 3000);
  // Every evaluation improving: no stop. The first point has no best before it.
  EXPECT_FALSE(FindGrowthStop(std::vector<HeldOutPoint>(curve.begin(), curve.begin() + 2), 1000,
                              0.002)
                   .has_value());
  EXPECT_FALSE(FindGrowthStop({{100, 10.0, 500}}, 1000, 0.002).has_value());
  // A gain smaller than the tolerance is no gain: +0.005 dB against 0.2%.
  EXPECT_EQ(FindGrowthStop(HeldOutWithCounts({20, 20.005}), 1000, 0.002)->iteration, 200);
  EXPECT_FALSE(FindGrowthStop(HeldOutWithCounts({20, 20.005}), 1000, 0.0).has_value());
}

TEST(GrowthStop, OnlyWhileDensifyingAndOnlyWhereACountWasRecorded) {
  std::vector<HeldOutPoint> curve = HeldOutWithCounts({20, 22, 21.9, 23, 22.5});
  // Densification ends at 300: the points at 300 and after cannot stop a growth that is over.
  EXPECT_FALSE(FindGrowthStop(curve, 300, 0.002).has_value());
  EXPECT_EQ(FindGrowthStop(curve, 301, 0.002)->iteration, 300);
  // A checkpoint from before counts were kept: its points never freeze the count.
  curve[2].gaussians = 0;
  EXPECT_EQ(FindGrowthStop(curve, 1000, 0.002)->iteration, 500);
  // An unscored (non-finite) evaluation is no gain.
  const double nan = std::nan("");
  EXPECT_EQ(FindGrowthStop(HeldOutWithCounts({20, nan, 25}), 1000, 0.002)->iteration, 200);
}

}  // namespace
}  // namespace hdr4d::method
