#include "baselines/bilateral_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "baselines/test_util.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {
namespace {

using namespace testing;  // baselines/test_util.h

// The bilateral filter by its definition: Gaussian spatial and range weights over a window of
// 3 sigma, normalised.
std::vector<double> BruteForce(const std::vector<double>& image,
                               int width,
                               int height,
                               double sigma_space,
                               double sigma_range) {
  std::vector<double> out(image.size());
  const int r = int(std::ceil(3 * sigma_space));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double center = image[y * width + x];
      double sum = 0, weight = 0;
      for (int v = std::max(0, y - r); v <= std::min(height - 1, y + r); ++v) {
        for (int u = std::max(0, x - r); u <= std::min(width - 1, x + r); ++u) {
          const double q = image[v * width + u];
          const double d2 = double((u - x) * (u - x) + (v - y) * (v - y));
          const double w = std::exp(-d2 / (2 * sigma_space * sigma_space) -
                                    (q - center) * (q - center) / (2 * sigma_range * sigma_range));
          sum += w * q;
          weight += w;
        }
      }
      out[y * width + x] = sum / weight;
    }
  }
  return out;
}

// A smooth gradient with a strong step and fine noise: what a log-luminance image looks like.
std::vector<double> TestImage(int width, int height, unsigned seed) {
  std::vector<double> image = Uniform(std::size_t(width) * height, -0.15, 0.15, seed);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image[y * width + x] += 0.03 * x + 0.5 * std::sin(0.2 * y) + (x > width / 2 ? 4.0 : 0.0);
    }
  }
  return image;
}

TEST(BilateralGrid, ConstantImagesAreUnchanged) {
  const std::vector<double> image(35, 2.5);
  const BilateralGrid<double> grid(image.data(), 7, 5, 1.5, 0.9);
  std::vector<double> out(35);
  grid.Filter(image.data(), out.data());
  for (double v : out) EXPECT_NEAR(v, 2.5, 1e-12);
  EXPECT_EQ(grid.cells_x(), 6);  // floor(6 / 1.5) + 2
  EXPECT_EQ(grid.cells_y(), 4);
  EXPECT_EQ(grid.cells_z(), 2);
}

TEST(BilateralGrid, ApproximatesTheBilateralFilter) {
  const int w = 64, h = 48;
  const double sigma_space = 3.0, sigma_range = 0.92;
  const std::vector<double> image = TestImage(w, h, 5);
  const std::vector<double> exact = BruteForce(image, w, h, sigma_space, sigma_range);
  const BilateralGrid<double> grid(image.data(), w, h, sigma_space, sigma_range);
  std::vector<double> out(image.size());
  grid.Filter(image.data(), out.data());
  double error = 0, smoothing = 0, max_error = 0;
  for (std::size_t p = 0; p < image.size(); ++p) {
    error += std::abs(out[p] - exact[p]);
    smoothing += std::abs(exact[p] - image[p]);
    max_error = std::max(max_error, std::abs(out[p] - exact[p]));
  }
  error /= double(image.size());
  smoothing /= double(image.size());
  EXPECT_LT(error, 0.2 * smoothing);  // measured: 0.14
  EXPECT_LT(max_error, 0.1);          // measured: 0.043 (the step is 4)
}

TEST(BilateralGrid, KeepsStrongEdgesWhereAGaussianBlurs) {
  const int w = 40, h = 10;
  std::vector<double> image(w * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) image[y * w + x] = x < w / 2 ? 0.0 : 5.0;
  }
  std::vector<double> edge_aware(image.size()), blurred(image.size());
  BilateralGrid<double>(image.data(), w, h, 3.0, 0.92).Filter(image.data(), edge_aware.data());
  BilateralGrid<double>(image.data(), w, h, 3.0, 1e3).Filter(image.data(), blurred.data());
  const int left = 5 * w + w / 2 - 1, right = left + 1;
  EXPECT_LT(edge_aware[left], 0.05);
  EXPECT_GT(edge_aware[right], 4.95);
  EXPECT_GT(blurred[left], 1.0);
  EXPECT_LT(blurred[right], 4.0);
}

TEST(BilateralGrid, BackwardIsTheTransposeOfTheFilter) {
  const int w = 9, h = 7;
  const std::vector<double> guide = TestImage(w, h, 8);
  const BilateralGrid<double> grid(guide.data(), w, h, 1.7, 0.9);
  const std::vector<double> values = Uniform(w * h, -2.0, 2.0, 9);
  const std::vector<double> weights = Uniform(w * h, -1.0, 1.0, 10);
  std::vector<double> grad(w * h);
  grid.FilterBackward(weights.data(), grad.data());
  ExpectFdMatch(
      [&](const std::vector<double>& v) {
        std::vector<double> out(v.size());
        grid.Filter(v.data(), out.data());
        return Dot(weights, out);
      },
      values, grad);
}

TEST(BilateralGrid, IsIdenticalAtAnyThreadCount) {
  const int w = 300, h = 200;
  const std::vector<float> guide = Uniform<float>(w * h, -5, 5, 3);
  std::vector<std::vector<float>> out;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    const BilateralGrid<float> grid(guide.data(), w, h, 4.0, 0.92);
    std::vector<float> filtered(w * h), back(w * h);
    grid.Filter(guide.data(), filtered.data());
    grid.FilterBackward(guide.data(), back.data());
    filtered.insert(filtered.end(), back.begin(), back.end());
    out.push_back(filtered);
  }
  EXPECT_EQ(std::memcmp(out[0].data(), out[1].data(), out[0].size() * sizeof(float)), 0);
}

TEST(BilateralGrid, NonFiniteGuideValuesAreSafe) {
  std::vector<double> guide = TestImage(12, 8, 4);
  guide[5] = std::numeric_limits<double>::quiet_NaN();
  guide[17] = std::numeric_limits<double>::infinity();
  guide[30] = -std::numeric_limits<double>::infinity();
  const std::vector<double> values = Uniform(96, 0.0, 1.0, 2);
  const BilateralGrid<double> grid(guide.data(), 12, 8, 1.0, 0.9);
  std::vector<double> out(96);
  grid.Filter(values.data(), out.data());
  for (double v : out) EXPECT_TRUE(std::isfinite(v) && v >= 0.0 && v <= 1.0);
  // An all-NaN guide still gives a valid (purely spatial) filter.
  const std::vector<double> nan(96, std::numeric_limits<double>::quiet_NaN());
  BilateralGrid<double>(nan.data(), 12, 8, 1.0, 0.9).Filter(values.data(), out.data());
  for (double v : out) EXPECT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace hdr4d::baselines
