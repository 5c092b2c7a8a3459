#include "method/run/export_ply.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/image/image.h"
#include "core/files/json_util.h"
#include "method/gaussian/constants.h"
#include "method/gaussian/rotation4d.h"
#include "method/gaussian/slice.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

// The values of one vertex: x y z, normals, f_dc, f_rest (at most 3 x 15), opacity, scale, rot.
struct PlyRow {
  float values[62];
};

void CheckExportable(const GaussianModel& model,
                     float time_duration,
                     const fs::path& path,
                     const ExportDisplay* display) {
  const bool hdr = model.color_mode != ColorMode::kLdr;
  if (hdr && !display) {
    Fail(
        "{}: this model has log-HDR colours; a 3DGS viewer expects display colours (give the "
        "tone mapping to export with)",
        path.string());
  }
  if (hdr && display->tone_mapper && !display->tone_mapper->pointwise()) {
    Fail(
        "{}: the '{}' tone mapper works on whole images, not on Gaussians; cannot export "
        "display colours with it",
        path.string(), display->tone_mapper->config().kind);
  }
  if (!(time_duration > 0)) Fail("export-ply: time duration must be positive");
  if (model.channels != 3)
    Fail("{}: 3DGS .ply holds RGB; this model has {} channels", path.string(), model.channels);
}

// Gaussian i as a 3D Gaussian at `time`: its mean, covariance and temporal marginal (1 for a
// static model); nullopt when the slice culls it.
struct Slice3D {
  Vec3<double> mean;
  Mat3<double> cov;
  double marginal = 1.0;
};

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

// Gaussian i's vertex. The temporal basis is folded into plain SH coefficients at `time`, the
// marginal into the opacity; a log-HDR model (`hdr`) gets zeros for the view-dependent terms.
PlyRow MakeRow(const GaussianModel& model,
               std::size_t i,
               const Slice3D& slice,
               float time,
               float time_duration,
               bool hdr) {
  const int functions = model.basis.sh_functions();  // per time block
  const int time_blocks = model.temporal ? model.basis.max_time_degree + 1 : 1;
  // Principal axes of the 3D covariance give a 3DGS scale and rotation.
  Eigen::SelfAdjointEigenSolver<Mat3<double>> eig(slice.cov);
  Mat3<double> axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) *= -1;
  const Eigen::Quaterniond q(axes);
  // Temporal cosine weights at this time fold the time blocks into plain SH coefficients.
  double weight[3] = {1, 0, 0};
  const double dt = model.t[i] - time;
  for (int n = 1; n < time_blocks; ++n)
    weight[n] = std::cos(2 * std::numbers::pi * n * dt / time_duration);
  auto coefficient = [&](int lm, int c) {
    double v = 0;
    for (int n = 0; n < time_blocks; ++n) {
      const int k = lm + functions * n;
      v += weight[n] * (k == 0 ? model.color_dc[i * 3 + c]
                               : model.color_rest[i * model.rest_stride() + (k - 1) * 3 + c]);
    }
    return static_cast<float>(v);
  };
  PlyRow row{};
  int j = 0;
  for (int a = 0; a < 3; ++a) row.values[j++] = static_cast<float>(slice.mean[a]);
  for (int a = 0; a < 3; ++a) row.values[j++] = 0.0f;  // normals (unused by viewers)
  for (int c = 0; c < 3; ++c) row.values[j++] = coefficient(0, c);
  for (int c = 0; c < 3; ++c) {
    for (int lm = 1; lm < functions; ++lm) row.values[j++] = hdr ? 0.0f : coefficient(lm, c);
  }
  const double opacity =
      std::clamp(slice.marginal / (1.0 + std::exp(-static_cast<double>(model.opacity_logit[i]))),
                 1e-7, 1 - 1e-7);
  row.values[j++] = static_cast<float>(std::log(opacity / (1 - opacity)));
  for (int a = 0; a < 3; ++a)
    row.values[j++] = static_cast<float>(0.5 * std::log(std::max(eig.eigenvalues()[a], 1e-20)));
  row.values[j++] = static_cast<float>(q.w());
  row.values[j++] = static_cast<float>(q.x());
  row.values[j++] = static_cast<float>(q.y());
  row.values[j++] = static_cast<float>(q.z());
  HDR4D_CHECK(j == 3 + 3 + 3 + 3 * (functions - 1) + 1 + 3 + 4);
  return row;
}

// A log-HDR model's DC coefficients: log-HDR colour -> display colour -> the DC coefficient of
// that colour.
void MapDcToDisplay(const ExportDisplay& display, std::vector<PlyRow>* rows) {
  const std::size_t n = rows->size();
  std::vector<float> log_hdr(n * 3), ldr(n * 3);
  for (std::size_t r = 0; r < n; ++r) {
    const float* dc = &(*rows)[r].values[6];
    for (int c = 0; c < 3; ++c) log_hdr[r * 3 + c] = kShC0 * dc[c] + kColorOffset;
  }
  if (display.tone_mapper) {
    display.tone_mapper->BeginFrame(display.frame);
    display.tone_mapper->Map(log_hdr.data(), n, ldr.data());
  } else {
    const float exposure = std::exp(display.frame.log_exposure);
    for (std::size_t k = 0; k < ldr.size(); ++k)
      ldr[k] =
          LinearToSrgb(std::clamp(std::exp(std::min(log_hdr[k], 30.0f)) * exposure, 0.0f, 1.0f));
  }
  for (std::size_t r = 0; r < n; ++r)
    for (int c = 0; c < 3; ++c) (*rows)[r].values[6 + c] = (ldr[r * 3 + c] - kColorOffset) / kShC0;
}

std::string PlyHeader(std::size_t vertices, int rest_per_channel) {
  std::string header =
      fmt::format("ply\nformat binary_little_endian 1.0\nelement vertex {}\n", vertices);
  for (const char* name : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    header += fmt::format("property float {}\n", name);
  for (int k = 0; k < 3 * rest_per_channel; ++k)
    header += fmt::format("property float f_rest_{}\n", k);
  header += "property float opacity\n";
  for (const char* name : {"scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    header += fmt::format("property float {}\n", name);
  header += "end_header\n";
  return header;
}

}  // namespace

std::size_t ExportSlicePly(const GaussianModel& model,
                           float time,
                           float time_duration,
                           const fs::path& path,
                           const ExportDisplay* display) {
  CheckExportable(model, time_duration, path, display);
  const bool hdr = model.color_mode != ColorMode::kLdr;
  std::vector<PlyRow> rows;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const std::optional<Slice3D> slice = SliceGaussian(model, i, time);
    if (slice) rows.push_back(MakeRow(model, i, *slice, time, time_duration, hdr));
  }
  if (hdr && !rows.empty()) MapDcToDisplay(*display, &rows);
  const int rest_per_channel = model.basis.sh_functions() - 1;
  const std::string header = PlyHeader(rows.size(), rest_per_channel);
  const std::size_t num_values = 3 + 3 + 3 + 3 * rest_per_channel + 1 + 3 + 4;
  WriteFileAtomic(path, [&](std::ostream& out) {
    out << header;
    for (const PlyRow& r : rows)
      out.write(reinterpret_cast<const char*>(r.values), num_values * sizeof(float));
  });
  return rows.size();
}

}  // namespace hdr4d::method
