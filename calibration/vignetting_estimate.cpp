#include "calibration/vignetting_estimate.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hdr4d {
namespace {

constexpr double kOutlier = 0.3;  // |residual| in ln units left out of a fit
constexpr double kMinV = -0.5, kMaxV = 0.9;

double Falloff(double v, double r2) { return std::log(std::max(1e-6, 1 - v * r2)); }

// The standard error of each camera's v at the solution: the inliers' residual variance times
// the (v, v) element of the inverse of J^T J for (a_c, v_c), the points' means held (so it
// is a lower bound; a camera whose falloff is not resolved by its radii gets a large one).
std::vector<double> StandardErrors(const std::vector<std::vector<VignettingSample>>& points,
                                   const std::vector<double>& mean, const std::vector<double>& a,
                                   const std::vector<double>& v, const std::vector<int>& count) {
  const std::size_t nc = v.size();
  std::vector<double> se(nc, std::numeric_limits<double>::infinity());
  for (std::size_t c = 0; c < nc; ++c) {
    if (count[c] < 20) continue;
    double jtj00 = 0, jtj01 = 0, jtj11 = 0, rr = 0;
    for (std::size_t p = 0; p < points.size(); ++p)
      for (const VignettingSample& s : points[p]) {
        if (static_cast<std::size_t>(s.camera) != c) continue;
        const double r = s.log_radiance - mean[p] - a[c] - Falloff(v[c], s.r2);
        if (std::abs(r) > kOutlier) continue;
        const double dv = -s.r2 / std::max(1e-6, 1 - v[c] * s.r2);
        jtj00 += 1;
        jtj01 += dv;
        jtj11 += dv * dv;
        rr += r * r;
      }
    const double det = jtj00 * jtj11 - jtj01 * jtj01;
    if (jtj00 > 2 && det > 1e-12) se[c] = std::sqrt(rr / (jtj00 - 2) * jtj00 / det);
  }
  return se;
}

}  // namespace

std::vector<double> EstimateVignetting(const std::vector<std::vector<VignettingSample>>& points, int cameras,
                                       std::vector<double>* standard_error) {
  const std::size_t nc = static_cast<std::size_t>(std::max(cameras, 0));
  std::vector<double> a(nc, 0), v(nc, 0);
  std::vector<int> count(nc, 0);
  for (const auto& seen : points)
    for (const VignettingSample& s : seen)
      if (s.camera >= 0 && static_cast<std::size_t>(s.camera) < nc) ++count[s.camera];
  std::vector<double> mean(points.size(), 0);
  for (int outer = 0; outer < 30; ++outer) {
    for (std::size_t p = 0; p < points.size(); ++p) {
      double sum = 0;
      for (const VignettingSample& s : points[p]) sum += s.log_radiance - a[s.camera] - Falloff(v[s.camera], s.r2);
      mean[p] = points[p].empty() ? 0 : sum / points[p].size();
    }
    for (std::size_t c = 0; c < nc; ++c) {
      if (count[c] < 20) continue;
      for (int gn = 0; gn < 3; ++gn) {  // Gauss-Newton on (a_c, v_c)
        double jtj00 = 0, jtj01 = 0, jtj11 = 0, jtr0 = 0, jtr1 = 0;
        for (std::size_t p = 0; p < points.size(); ++p)
          for (const VignettingSample& s : points[p]) {
            if (static_cast<std::size_t>(s.camera) != c) continue;
            const double r = s.log_radiance - mean[p] - a[c] - Falloff(v[c], s.r2);
            if (std::abs(r) > kOutlier) continue;
            const double dv = -s.r2 / std::max(1e-6, 1 - v[c] * s.r2);  // d Falloff / d v
            jtj00 += 1;
            jtj01 += dv;
            jtj11 += dv * dv;
            jtr0 += r;
            jtr1 += dv * r;
          }
        const double det = jtj00 * jtj11 - jtj01 * jtj01;
        if (!(det > 1e-12)) break;
        a[c] += (jtj11 * jtr0 - jtj01 * jtr1) / det;
        v[c] = std::clamp(v[c] + (jtj00 * jtr1 - jtj01 * jtr0) / det, kMinV, kMaxV);
      }
    }
    double centre = 0;  // the gains' gauge: their mean log is 0 (the points' means carry the scale)
    for (double x : a) centre += x / nc;
    for (double& x : a) x -= centre;
  }
  for (std::size_t c = 0; c < nc; ++c)
    if (count[c] < 20) v[c] = 0;
  if (standard_error) *standard_error = StandardErrors(points, mean, a, v, count);
  return v;
}

}  // namespace hdr4d
