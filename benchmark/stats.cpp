#include "benchmark/stats.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <map>

namespace hdr4d::bench {
namespace {

// Continued fraction of the incomplete beta function (modified Lentz's method).
double BetaContinuedFraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300, kEps = 1e-15;
  double c = 1, d = 1 - (a + b) * x / (a + 1);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1 / d;
  double h = d;
  for (int m = 1; m <= 1000; ++m) {
    const double m2 = 2.0 * m;
    // Even step.
    double num = m * (b - m) * x / ((a + m2 - 1) * (a + m2));
    d = 1 + num * d;
    c = 1 + num / c;
    d = std::abs(d) < kTiny ? 1 / kTiny : 1 / d;
    if (std::abs(c) < kTiny) c = kTiny;
    h *= d * c;
    // Odd step.
    num = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1));
    d = 1 + num * d;
    c = 1 + num / c;
    d = std::abs(d) < kTiny ? 1 / kTiny : 1 / d;
    if (std::abs(c) < kTiny) c = kTiny;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < kEps) break;
  }
  return h;
}

}  // namespace

double Mean(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double SampleStdDev(const std::vector<double>& v) {
  if (v.size() < 2) return 0;
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

double RegularizedIncompleteBeta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  // The fraction converges fast for x < (a + 1) / (a + b + 2); use the symmetry otherwise.
  if (x < (a + 1) / (a + b + 2)) return std::exp(log_front) * BetaContinuedFraction(a, b, x) / a;
  return 1 - std::exp(log_front) * BetaContinuedFraction(b, a, 1 - x) / b;
}

double StudentTwoSidedP(double t, double dof) {
  if (!std::isfinite(t)) return 0;
  return RegularizedIncompleteBeta(dof / 2, 0.5, dof / (dof + t * t));
}

std::string PairedTest::Verdict() const {
  if (!testable) return "not testable (one seed per scene: no seed noise to compare with)";
  if (seed_sd == 0 && mean_difference == 0) return "identical";
  const char* noise = over_scenes ? "scene-to-scene noise" : "seed noise";
  return fmt::format("{} {} (p = {:.3g})", significant ? "exceeds" : "within", noise, p);
}

PairedTest PairedSeedTest(const std::vector<PairedValue>& values, double alpha) {
  PairedTest t;
  std::map<std::string, std::vector<double>> by_scene;
  for (const PairedValue& v : values) {
    if (std::isfinite(v.a) && std::isfinite(v.b)) by_scene[v.scene].push_back(v.a - v.b);
  }
  std::vector<double> all;
  double within = 0;
  for (const auto& [scene, d] : by_scene) {
    const double m = Mean(d);
    for (double x : d) {
      within += (x - m) * (x - m);
      all.push_back(x);
    }
  }
  t.pairs = static_cast<int>(all.size());
  t.scenes = static_cast<int>(by_scene.size());
  if (t.pairs == 0) return t;
  t.mean_difference = Mean(all);
  t.dof = t.pairs - t.scenes;
  if (t.dof < 1) return t;
  t.testable = true;
  t.seed_sd = std::sqrt(within / t.dof);
  if (t.seed_sd == 0) {
    // No seed noise at all: any difference exceeds it, none is identical.
    t.t = t.mean_difference == 0 ? 0 : std::copysign(std::numeric_limits<double>::infinity(),
                                                     t.mean_difference);
    t.p = t.mean_difference == 0 ? 1 : 0;
  } else {
    t.t = t.mean_difference / (t.seed_sd / std::sqrt(static_cast<double>(t.pairs)));
    t.p = StudentTwoSidedP(t.t, t.dof);
  }
  t.significant = t.p < alpha;
  return t;
}

}  // namespace hdr4d::bench
