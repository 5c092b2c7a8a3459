// Statistics of the benchmark tables: means, sample standard deviations, and the paired test
// that says whether the difference between two table rows is larger than seed noise.
#pragma once

#include <string>
#include <vector>

namespace hdr4d::bench {

double Mean(const std::vector<double>& v);
// Sample standard deviation (n - 1); 0 for fewer than two values.
double SampleStdDev(const std::vector<double>& v);

// Regularised incomplete beta function I_x(a, b), by the continued fraction (modified Lentz).
double RegularizedIncompleteBeta(double a, double b, double x);
// Two-sided p-value of Student's t statistic with `dof` degrees of freedom.
double StudentTwoSidedP(double t, double dof);

// One matched pair of table cells: the same scene and seed under two rows.
struct PairedValue {
  std::string scene;
  double a = 0, b = 0;
};

// Paired test of rows A and B, pairs matched by scene and seed. With d = a - b:
//   mean  = mean of all d (n pairs over S scenes)
//   noise = the seed-to-seed variance of d, pooled within scenes:
//           s^2 = sum over scenes of sum (d - mean of d in that scene)^2 / (n - S)
//   t     = mean / sqrt(s^2 / n), two-sided p from Student's t with n - S degrees of freedom.
// Scenes are fixed blocks: the question is whether, on these scenes, A and B differ by more
// than retraining with another seed moves a result. It needs at least one scene with two or
// more seeds (n > S); otherwise `testable` is false.
struct PairedTest {
  int pairs = 0, scenes = 0;
  double mean_difference = 0;
  double seed_sd = 0;  // sqrt(s^2): the seed noise of a difference
  double t = 0, dof = 0, p = 1;
  bool testable = false;
  bool significant = false;  // p < alpha
  // Set by the tables where the seed test cannot decide (a submission with one seed): the
  // pairs are scenes, each row's mean over its seeds there, and the noise the differences'
  // spread over scenes (a paired t-test over scenes, n - 1 degrees of freedom).
  bool over_scenes = false;
  std::string Verdict() const;  // "exceeds seed noise (p = 0.003)", ...
};
PairedTest PairedSeedTest(const std::vector<PairedValue>& values, double alpha = 0.05);

}  // namespace hdr4d::bench
