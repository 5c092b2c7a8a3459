#include "method/run/slice3d.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "method/gaussian/slice.h"

namespace hdr4d::method {

std::optional<Slice3D> SliceGaussian(const GaussianModel& model, std::size_t i, float time) {
  Slice3D out;
  out.mean = Vec3<double>(model.xyz[i * 3], model.xyz[i * 3 + 1], model.xyz[i * 3 + 2]);
  const Vec4<double> ls(model.log_scales[i * 4], model.log_scales[i * 4 + 1],
                        model.log_scales[i * 4 + 2], model.log_scales[i * 4 + 3]);
  const Vec4<double> ql(model.rot_left[i * 4], model.rot_left[i * 4 + 1],
                        model.rot_left[i * 4 + 2], model.rot_left[i * 4 + 3]);
  if (!model.temporal) {
    out.cov = Covariance3D(Rotation3D(ql), Vec3<double>(ls.head<3>()));
    return out;
  }
  const Vec4<double> qr(model.rot_right[i * 4], model.rot_right[i * 4 + 1],
                        model.rot_right[i * 4 + 2], model.rot_right[i * 4 + 3]);
  const Slice<double> s =
      SliceAtTime(Vec4<double>(out.mean.x(), out.mean.y(), out.mean.z(), model.t[i]),
                  Covariance4D(Rotation4D(ql, qr), ls), static_cast<double>(time));
  if (!TemporallyVisible(s.marginal)) return std::nullopt;
  out.mean = s.mean;
  out.cov = s.cov;
  out.marginal = s.marginal;
  return out;
}

ScaleRotation PrincipalAxes(const Mat3<double>& cov) {
  Eigen::SelfAdjointEigenSolver<Mat3<double>> eig(cov);
  Mat3<double> axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) *= -1;
  const Eigen::Quaterniond q(axes);
  ScaleRotation out;
  // A degenerate axis (eigenvalue <= 0 from rounding) gets a tiny but finite scale.
  for (int a = 0; a < 3; ++a) out.log_scale[a] = 0.5 * std::log(std::max(eig.eigenvalues()[a], 1e-20));
  out.quaternion[0] = q.w();
  out.quaternion[1] = q.x();
  out.quaternion[2] = q.y();
  out.quaternion[3] = q.z();
  return out;
}

void FoldedShCoefficients(const GaussianModel& model,
                          std::size_t i,
                          float time,
                          float time_duration,
                          double* out) {
  const int functions = model.basis.sh_functions();
  const int time_blocks = model.temporal ? model.basis.max_time_degree + 1 : 1;
  const int channels = model.channels;
  // cos(2 pi n dt / T) of each time block at this time; block 0 is the constant 1.
  double weight[3] = {1, 0, 0};
  const double dt = static_cast<double>(model.t[i]) - time;
  for (int n = 1; n < time_blocks; ++n)
    weight[n] = std::cos(2 * std::numbers::pi * n * dt / time_duration);
  for (int lm = 0; lm < functions; ++lm) {
    for (int c = 0; c < channels; ++c) {
      double v = 0;
      for (int n = 0; n < time_blocks; ++n) {
        const int k = lm + functions * n;
        v += weight[n] * (k == 0 ? model.color_dc[i * channels + c]
                                 : model.color_rest[i * model.rest_stride() + (k - 1) * channels + c]);
      }
      out[lm * channels + c] = v;
    }
  }
}

}  // namespace hdr4d::method
