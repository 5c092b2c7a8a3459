#include "calibration/response_recovery.h"

#include <fmt/format.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>

#include "core/util/error.h"
#include "core/files/json_util.h"
#include "core/viz/plot.h"

namespace hdr4d {
namespace {

constexpr int kMidCode = 128;

// Debevec-Malik's hat weight: codes near black and white carry little information.
double HatWeight(int code) { return std::min(code, kResponseCodes - 1 - code) + 1.0; }

void CheckStacks(const std::vector<std::vector<Bracket>>& stacks) {
  if (stacks.empty()) Fail("response recovery: no bracketed stack given");
  const Image& first = stacks.front().front().image;
  for (const auto& stack : stacks) {
    if (stack.size() < 2)
      Fail("{}: response recovery needs at least two brackets of the same view, found {}",
           stack.empty() ? std::string("stack") : stack.front().name, stack.size());
    for (std::size_t j = 0; j < stack.size(); ++j) {
      const Bracket& b = stack[j];
      if (!(b.exposure > 0) || !std::isfinite(b.exposure))
        Fail("{}: exposure time {} is not a positive number", b.name, b.exposure);
      if (b.image.channels() != first.channels())
        Fail("{}: {} channels, the other brackets have {}", b.name, b.image.channels(), first.channels());
      if (!b.image.SameShape(stack.front().image))
        Fail("{}: size {} differs from {} ({})", b.name, b.image.ShapeString(),
             stack.front().name, stack.front().image.ShapeString());
      for (std::size_t k = 0; k < j; ++k)
        if (stack[k].exposure == b.exposure)
          Fail("{}: same exposure time {} s as {}; brackets need distinct exposures", b.name,
               b.exposure, stack[k].name);
    }
  }
}

// Pixel indices sampled from each stack, spread over the stacks.
std::vector<std::vector<std::size_t>> SamplePixels(const std::vector<std::vector<Bracket>>& stacks,
                                                   int samples) {
  std::mt19937 rng(12345);
  std::vector<std::vector<std::size_t>> picked(stacks.size());
  const int per_stack = std::max(1, samples / static_cast<int>(stacks.size()));
  for (std::size_t s = 0; s < stacks.size(); ++s) {
    const std::size_t n = stacks[s].front().image.num_pixels();
    std::uniform_int_distribution<std::size_t> pick(0, n - 1);
    for (int i = 0; i < per_stack && i < static_cast<int>(n); ++i) picked[s].push_back(pick(rng));
  }
  return picked;
}

// Non-decreasing (strictly, by a hair, so the curve stays invertible) and x(128) = 1.
std::array<double, kResponseCodes> Normalise(std::array<double, kResponseCodes> x) {
  for (int z = 0; z < kResponseCodes; ++z)
    if (!std::isfinite(x[z]) || x[z] <= 0) x[z] = z > 0 ? x[z - 1] : 1e-6;
  for (int z = 1; z < kResponseCodes; ++z) x[z] = std::max(x[z], x[z - 1] * (1 + 1e-9));
  const double mid = x[kMidCode];
  for (double& v : x) v /= mid;
  return x;
}

std::array<double, kResponseCodes> SolveDebevec(const std::vector<std::vector<Bracket>>& stacks,
                                                const std::vector<std::vector<std::size_t>>& pixels,
                                                int channel,
                                                double smoothness) {
  int num_samples = 0;
  for (const auto& p : pixels) num_samples += static_cast<int>(p.size());
  const int n = kResponseCodes + num_samples;  // g(0..255), then ln E per sample
  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<double> rhs;
  int row = 0;
  int sample = 0;
  for (std::size_t s = 0; s < stacks.size(); ++s) {
    for (std::size_t pixel : pixels[s]) {
      for (const Bracket& b : stacks[s]) {
        const int z = CodeOf(b.image.data()[pixel * b.image.channels() + channel]);
        const double w = HatWeight(z);
        triplets.emplace_back(row, z, w);
        triplets.emplace_back(row, kResponseCodes + sample, -w);
        rhs.push_back(w * std::log(b.exposure));
        ++row;
      }
      ++sample;
    }
  }
  triplets.emplace_back(row++, kMidCode, 1.0);  // fixes the unknown scale: g(128) = 0
  rhs.push_back(0.0);
  for (int z = 1; z < kResponseCodes - 1; ++z) {
    const double w = smoothness * HatWeight(z);
    triplets.emplace_back(row, z - 1, w);
    triplets.emplace_back(row, z, -2 * w);
    triplets.emplace_back(row, z + 1, w);
    rhs.push_back(0.0);
    ++row;
  }
  Eigen::SparseMatrix<double> a(row, n);
  a.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::Map<const Eigen::VectorXd> b(rhs.data(), row);
  const Eigen::SparseMatrix<double> normal = a.transpose() * a;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) Fail("response recovery: the Debevec system is singular");
  const Eigen::VectorXd solution = solver.solve(a.transpose() * b);
  std::array<double, kResponseCodes> x;
  for (int z = 0; z < kResponseCodes; ++z) x[z] = std::exp(std::clamp(solution[z], -700.0, 700.0));
  return Normalise(x);
}

// Robertson, Borman & Stevenson: alternate the radiance of every pixel given the curve and
// the curve (the mean exposure behind each code) given the radiances. Clipped codes (0, 255)
// carry no weight: their mean exposure says nothing about the curve and would drag every
// pixel that clips in some bracket.
std::array<double, kResponseCodes> SolveRobertson(const std::vector<std::vector<Bracket>>& stacks,
                                                  int channel,
                                                  int iterations) {
  auto weight = [](int z) {
    if (z == 0 || z == kResponseCodes - 1) return 0.0;
    const double d = (z - 127.5) / 127.5;
    return std::exp(-4.0 * d * d);
  };
  std::array<double, kResponseCodes> x;
  for (int z = 0; z < kResponseCodes; ++z) x[z] = (z + 0.5) / (kMidCode + 0.5);
  for (int it = 0; it < iterations; ++it) {
    std::array<double, kResponseCodes> sum{}, count{};
    for (const auto& stack : stacks) {
      const std::size_t n = stack.front().image.num_pixels();
      const int channels = stack.front().image.channels();
      for (std::size_t p = 0; p < n; ++p) {
        double num = 0, den = 0;
        for (const Bracket& b : stack) {
          const int z = CodeOf(b.image.data()[p * channels + channel]);
          num += weight(z) * b.exposure * x[z];
          den += weight(z) * b.exposure * b.exposure;
        }
        if (!(den > 0)) continue;  // clipped in every bracket
        const double radiance = num / den;
        for (const Bracket& b : stack) {
          const int z = CodeOf(b.image.data()[p * channels + channel]);
          sum[z] += radiance * b.exposure;
          count[z] += 1;
        }
      }
    }
    for (int z = 1; z < kResponseCodes - 1; ++z)
      if (count[z] > 0) x[z] = sum[z] / count[z];
    // Codes never seen: interpolate between seen neighbours; below the darkest go linearly to 0,
    // above the brightest stay flat (stale values would bias every pixel showing such a code).
    for (int z = 0; z < kResponseCodes; ++z) {
      if (count[z] > 0 && z > 0 && z < kResponseCodes - 1) continue;
      int lo = z - 1, hi = z + 1;
      while (lo >= 1 && count[lo] == 0) --lo;
      while (hi < kResponseCodes - 1 && count[hi] == 0) ++hi;
      const bool has_lo = lo >= 1, has_hi = hi < kResponseCodes - 1;
      if (has_lo && has_hi) x[z] = x[lo] + (x[hi] - x[lo]) * (z - lo) / double(hi - lo);
      else if (has_hi) x[z] = x[hi] * (z + 0.5) / (hi + 0.5);
      else if (has_lo) x[z] = x[lo];
    }
    const double mid = x[kMidCode] > 0 ? x[kMidCode] : 1.0;
    for (double& v : x) v /= mid;  // only the scale while iterating; monotone at the end
  }
  return Normalise(x);
}

}  // namespace

int CodeOf(float value01) {
  if (!(value01 > 0)) return 0;  // also NaN
  return std::min(kResponseCodes - 1, static_cast<int>(std::lround(value01 * (kResponseCodes - 1))));
}

double CameraResponse::Linearize(int channel, double value01) const {
  const auto& x = inverse[std::clamp<std::size_t>(channel, 0, inverse.size() - 1)];
  if (!(value01 > 0)) return x[0];
  const double code = std::min(1.0, value01) * (kResponseCodes - 1);
  const int lo = std::min(kResponseCodes - 2, static_cast<int>(code));
  const double f = code - lo;
  return x[lo] + f * (x[lo + 1] - x[lo]);
}

double CameraResponse::Encode(int channel, double exposure) const {
  const auto& x = inverse[std::clamp<std::size_t>(channel, 0, inverse.size() - 1)];
  if (!(exposure > x[0])) return 0.0;
  if (exposure > x[kResponseCodes - 1]) return 1.0;
  // x is non-decreasing: the first code at or above the exposure, interpolated from the one below.
  const int hi = static_cast<int>(std::lower_bound(x.begin(), x.end(), exposure) - x.begin());
  const int lo = hi - 1;
  const double span = x[hi] - x[lo];
  const double f = span > 0 ? (exposure - x[lo]) / span : 0.0;
  return (lo + f) / (kResponseCodes - 1);
}

CameraResponse RecoverResponse(const std::vector<std::vector<Bracket>>& stacks,
                               const ResponseOptions& options) {
  CheckStacks(stacks);
  if (options.samples < 1) Fail("response recovery: --samples must be positive");
  if (!(options.smoothness >= 0)) Fail("response recovery: smoothness must be >= 0");
  CameraResponse response;
  const int channels = stacks.front().front().image.channels();
  if (options.robertson) {
    if (options.robertson_iterations < 1) Fail("response recovery: Robertson needs at least one iteration");
    response.method = "robertson";
    for (int c = 0; c < channels; ++c)
      response.inverse.push_back(SolveRobertson(stacks, c, options.robertson_iterations));
    return response;
  }
  response.method = "debevec";
  const auto pixels = SamplePixels(stacks, options.samples);
  for (int c = 0; c < channels; ++c)
    response.inverse.push_back(SolveDebevec(stacks, pixels, c, options.smoothness));
  return response;
}

void WriteResponseCsv(const std::string& path, const CameraResponse& response) {
  std::string text = "# inverse camera response: relative exposure per code, x(128) = 1\ncode";
  const char* names[] = {"r", "g", "b", "a"};
  for (std::size_t c = 0; c < response.inverse.size(); ++c)
    text += fmt::format(",{}", c < 4 ? names[c] : "c");
  text += "\n";
  for (int z = 0; z < kResponseCodes; ++z) {
    text += fmt::format("{}", z);
    for (const auto& x : response.inverse) text += fmt::format(",{:.9g}", x[z]);
    text += "\n";
  }
  WriteTextFileAtomic(path, text);
}

void WriteResponsePlot(const std::string& path, const CameraResponse& response) {
  std::vector<PlotSeries> series;
  const char* names[] = {"red", "green", "blue", "alpha"};
  const std::array<float, 3> colors[] = {{0.8f, 0.1f, 0.1f}, {0.1f, 0.6f, 0.1f}, {0.1f, 0.2f, 0.8f}, {0.3f, 0.3f, 0.3f}};
  for (std::size_t c = 0; c < response.inverse.size() && c < 4; ++c) {
    PlotSeries s;
    s.name = names[c];
    s.color = response.inverse.size() == 1 ? colors[3] : colors[c];
    for (int z = 1; z < kResponseCodes; ++z) {
      s.x.push_back(response.inverse[c][z]);
      s.y.push_back(z);
    }
    series.push_back(std::move(s));
  }
  PlotOptions options;
  options.title = fmt::format("camera response ({})", response.method);
  options.x_label = "relative exposure (log)";
  options.y_label = "code";
  options.log_x = true;
  WritePlot(path, series, options);
}

}  // namespace hdr4d
