// The two per-chunk backwards of DtmCore::MapBackward (dtm_core.cpp): ScalarChunkBackward (the
// double and the non-SIMD float path) and SimdChunkTableBackward (the float SIMD table path),
// each driven through MapBackward + EndFrameBackward over several chunks with the frame (context,
// tables) held fixed, and compared with central differences in double of DtmCore<double>::Map:
// dL/dlog_hdr for every value, and the three curves' parameter gradients (what the chunk's node
// and direct gradients become through FrameToneCurve's backwards, whose own tests are in
// tone_curve_test.cpp). The context learner's parameters are not compared: their gradient is
// ContextLearnerBackward's (context_learner_test.cpp). The SIMD path runs on every compiled
// Highway target and is also compared with the scalar chunk.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "method/raster/simd_targets_for_test.h"
#include "method/tonemap/dtm_core.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::FdCheck;
using testing::FdVector;

constexpr int kNodes = 64;
constexpr int kLength = 5;
constexpr std::size_t kColours = 2 * kDtmChunk + 5;  // three chunks, the last one short

DtmShape Shape() {
  DtmShape s;
  s.context = {ContextKind::kGru, 2};
  s.curve = {2, 8};
  s.table_nodes = kNodes;
  return s;
}

// Parameters, window and values shared by both tests, all exactly representable in float (so the
// float cores and the double reference see the same inputs). Values sit in the middle of a table
// interval (a step of 1e-6 never crosses a node), most in [-8, 6] where the curves bend;
// `outside` adds values beyond the table (ScalarChunkBackward's direct branch).
struct Frame {
  DtmShape shape = Shape();
  std::vector<double> params, window, log_hdr, weights;
  double log_e = double(float(std::log(0.5)));
  explicit Frame(bool outside) {
    DtmCore<double> core(shape);
    params.resize(shape.NumParams());
    core.Init(11, params.data());
    for (std::size_t i = shape.CurveOffset(0); i < params.size(); ++i) params[i] *= 2.0;
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> u(0.1, 0.9), row(-2, 1), w(-1, 1);
    for (int i = 0; i < 3 * kLength; ++i) window.push_back(row(rng));
    const double step = (kTableXMax - kTableXMin) / (kNodes - 1);
    const int j0 = int((-8.0 - kTableXMin) / step), j1 = int((6.0 - kTableXMin) / step);
    for (std::size_t v = 0; v < 3 * kColours; ++v) {
      const int j = v % 11 == 0 ? int(u(rng) * (kNodes - 1)) : j0 + int(u(rng) * (j1 - j0));
      log_hdr.push_back(kTableXMin + (j + u(rng)) * step - log_e);
      weights.push_back(w(rng));
    }
    if (outside)
      for (std::size_t v : {std::size_t(7), std::size_t(100), std::size_t(5000), 3 * kColours - 1})
        log_hdr[v] = (v % 2 ? 30 : -40);
    for (auto* vec : {&params, &window, &log_hdr, &weights})
      for (double& x : *vec) x = double(float(x));
  }
  std::vector<double> Map(const std::vector<double>& p, const std::vector<double>& lh) const {
    DtmCore<double> core(shape);
    core.BeginFrame(p.data(), window.data(), kLength, log_e);
    std::vector<double> ldr(lh.size());
    core.Map(lh.data(), lh.size() / 3, ldr.data());
    return ldr;
  }
  double Loss(const std::vector<double>& p) const {
    const std::vector<double> ldr = Map(p, log_hdr);
    double l = 0;
    for (std::size_t v = 0; v < ldr.size(); ++v) l += weights[v] * ldr[v];
    return l;
  }
  // Each value maps on its own, so two maps of every value shifted by +-h give every dL/dlog_hdr.
  FdVector NumericValues(double h) const {
    std::vector<double> up = log_hdr, down = log_hdr;
    for (double& x : up) x += h;
    for (double& x : down) x -= h;
    const std::vector<double> a = Map(params, up), b = Map(params, down);
    FdVector g(a.size());
    for (std::size_t v = 0; v < a.size(); ++v) g(v) = weights[v] * (a[v] - b[v]) / (2 * h);
    return g;
  }
  std::size_t CurveFirst() const { return shape.CurveOffset(0); }
  std::size_t CurveCount() const { return params.size() - CurveFirst(); }
  FdVector NumericCurves(double h) const {
    const FdVector x0 = Eigen::Map<const FdVector>(params.data() + CurveFirst(), CurveCount());
    return testing::NumericGradient(
        [&](const FdVector& x) {
          std::vector<double> p = params;
          for (std::size_t k = 0; k < CurveCount(); ++k) p[CurveFirst() + k] = x(k);
          return Loss(p);
        },
        x0, h);
  }
};

template <typename T>
std::vector<T> Cast(const std::vector<double>& v) {
  return {v.begin(), v.end()};
}

// One frame's MapBackward + EndFrameBackward on a core of T: dL/dlog_hdr and the curves'
// parameter gradients, in double.
template <typename T>
void Backward(const Frame& f, bool simd, FdVector* dvalues, FdVector* dcurves) {
  DtmCore<T> core(f.shape);
  core.set_simd(simd);
  const std::vector<T> p = Cast<T>(f.params), win = Cast<T>(f.window);
  const std::vector<T> lh = Cast<T>(f.log_hdr), w = Cast<T>(f.weights);
  core.BeginFrame(p.data(), win.data(), kLength, T(f.log_e));
  std::vector<T> dlh(lh.size()), dp(p.size(), T(0));
  core.MapBackward(lh.data(), kColours, w.data(), dlh.data());
  core.EndFrameBackward(dp.data());
  using Vector = Eigen::Matrix<T, -1, 1>;
  *dvalues = Eigen::Map<const Vector>(dlh.data(), dlh.size()).template cast<double>();
  *dcurves =
      Eigen::Map<const Vector>(dp.data() + f.CurveFirst(), f.CurveCount()).template cast<double>();
}

// Double throughout: steps of 1e-6 (values) and 1e-6 (parameters) on smooth functions of size
// ~1, so the differences are good to ~1e-9 and the tolerance is 1e-6.
TEST(DtmChunkBackward, ScalarChunkBackwardMatchesFiniteDifferences) {
  constexpr FdCheck kFd{1e-6, 1e-6};
  const Frame f(/*outside=*/true);
  FdVector dvalues, dcurves;
  Backward<double>(f, false, &dvalues, &dcurves);
  kFd.ExpectMatch(dvalues, f.NumericValues(kFd.step));
  kFd.ExpectMatch(dcurves, f.NumericCurves(kFd.step));
}

// The float SIMD path against the double differences: float tables and float per-value
// gradients (node gradients summed in double), so 2e-4 of the largest component; against the
// float scalar chunk on the same inputs, 2e-5. Every value lies inside the table, so the SIMD
// chunk does all the work (no direct fallback).
TEST(DtmChunkBackward, SimdChunkTableBackwardMatchesFiniteDifferencesOnEveryTarget) {
  constexpr FdCheck kFd{1e-6, 2e-4};
  constexpr double kAgainstScalar = 2e-5;
  const Frame f(/*outside=*/false);
  const FdVector numeric_values = f.NumericValues(kFd.step);
  const FdVector numeric_curves = f.NumericCurves(kFd.step);
  FdVector scalar_values, scalar_curves;
  Backward<float>(f, false, &scalar_values, &scalar_curves);
  kFd.ExpectMatch(scalar_values, numeric_values);  // the float scalar chunk: the same bound
  kFd.ExpectMatch(scalar_curves, numeric_curves);
  const int ran = ForEachCompiledTarget([&] {
    FdVector dvalues, dcurves;
    Backward<float>(f, true, &dvalues, &dcurves);
    kFd.ExpectMatch(dvalues, numeric_values);
    kFd.ExpectMatch(dcurves, numeric_curves);
    testing::ExpectGradientsMatch(dvalues, scalar_values, kAgainstScalar);
    testing::ExpectGradientsMatch(dcurves, scalar_curves, kAgainstScalar);
  });
  EXPECT_GE(ran, MinimumTargetRuns());
}

}  // namespace
}  // namespace hdr4d::method
