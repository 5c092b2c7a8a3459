#include "benchmark/stats.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hdr4d::bench {
namespace {

TEST(Stats, MeanAndSampleStdDev) {
  EXPECT_DOUBLE_EQ(Mean({1, 2, 3, 4}), 2.5);
  EXPECT_NEAR(SampleStdDev({1, 2, 3, 4}), std::sqrt(5.0 / 3.0), 1e-12);
  EXPECT_EQ(SampleStdDev({7}), 0.0);
}

TEST(Stats, IncompleteBetaMatchesClosedForms) {
  // I_x(2, 3) = sum_{j=2..4} C(4, j) x^j (1-x)^(4-j): 11/16 at x = 1/2.
  EXPECT_NEAR(RegularizedIncompleteBeta(2, 3, 0.5), 11.0 / 16.0, 1e-12);
  // I_x(a, 1) = x^a; I_x(1, b) = 1 - (1-x)^b.
  EXPECT_NEAR(RegularizedIncompleteBeta(3.5, 1, 0.3), std::pow(0.3, 3.5), 1e-12);
  EXPECT_NEAR(RegularizedIncompleteBeta(1, 4.2, 0.7), 1 - std::pow(0.3, 4.2), 1e-12);
  EXPECT_EQ(RegularizedIncompleteBeta(2, 2, 0), 0);
  EXPECT_EQ(RegularizedIncompleteBeta(2, 2, 1), 1);
}

TEST(Stats, StudentPValuesMatchTables) {
  EXPECT_NEAR(StudentTwoSidedP(1.0, 1), 0.5, 1e-9);  // Cauchy: P(|T| > 1) = 1/2
  // Two-sided 5% critical values of Student's t (standard tables).
  EXPECT_NEAR(StudentTwoSidedP(12.7062047, 1), 0.05, 1e-6);
  EXPECT_NEAR(StudentTwoSidedP(2.5705818, 5), 0.05, 1e-6);
  EXPECT_NEAR(StudentTwoSidedP(2.2281389, 10), 0.05, 1e-6);
  EXPECT_NEAR(StudentTwoSidedP(2.7632625, 28), 0.01, 1e-6);
  EXPECT_NEAR(StudentTwoSidedP(0, 7), 1.0, 1e-12);
  EXPECT_NEAR(StudentTwoSidedP(-2.2281389, 10), 0.05, 1e-6);  // symmetric
}

std::vector<PairedValue> Pairs(const std::vector<std::vector<double>>& diffs) {
  std::vector<PairedValue> v;
  for (std::size_t s = 0; s < diffs.size(); ++s)
    for (double d : diffs[s]) v.push_back({"scene" + std::to_string(s), 20 + s + d, 20.0 + s});
  return v;
}

TEST(Stats, PairedTestComparesTheMeanDifferenceWithSeedNoise) {
  // Scene effects (20, 21, 22) cancel in the differences; the noise is within scenes only.
  const PairedTest big = PairedSeedTest(Pairs({{1.1, 0.9, 1.0}, {0.95, 1.05, 1.0}, {1.2, 0.8, 1.0}}));
  EXPECT_TRUE(big.testable);
  EXPECT_EQ(big.pairs, 9);
  EXPECT_EQ(big.scenes, 3);
  EXPECT_EQ(big.dof, 6);
  EXPECT_NEAR(big.mean_difference, 1.0, 1e-12);
  // Within-scene sums of squares: 0.02 + 0.005 + 0.08 over 6 degrees of freedom.
  EXPECT_NEAR(big.seed_sd, std::sqrt(0.105 / 6), 1e-12);
  EXPECT_NEAR(big.t, 1.0 / (std::sqrt(0.105 / 6) / 3), 1e-9);
  EXPECT_TRUE(big.significant);
  EXPECT_LT(big.p, 1e-5);

  const PairedTest small = PairedSeedTest(Pairs({{0.3, -0.2, 0.0}, {-0.3, 0.2, 0.1}, {0.2, -0.1, -0.1}}));
  EXPECT_TRUE(small.testable);
  EXPECT_FALSE(small.significant);
  EXPECT_GT(small.p, 0.5);
  EXPECT_NE(small.Verdict().find("within seed noise"), std::string::npos);
  EXPECT_NE(big.Verdict().find("exceeds seed noise"), std::string::npos);
}

TEST(Stats, OneSeedPerSceneCannotMeasureSeedNoise) {
  const PairedTest t = PairedSeedTest(Pairs({{1.0}, {2.0}, {3.0}}));
  EXPECT_FALSE(t.testable);
  EXPECT_FALSE(t.significant);
  EXPECT_NEAR(t.mean_difference, 2.0, 1e-12);
  EXPECT_NE(t.Verdict().find("not testable"), std::string::npos);
  EXPECT_FALSE(PairedSeedTest({}).testable);
}

TEST(Stats, NonFinitePairsAreLeftOut) {
  auto v = Pairs({{1.0, 1.2}, {0.8, 1.0}});
  v.push_back({"scene0", INFINITY, 1.0});
  const PairedTest t = PairedSeedTest(v);
  EXPECT_EQ(t.pairs, 4);
}

}  // namespace
}  // namespace hdr4d::bench
