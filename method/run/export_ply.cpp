#include "method/run/export_ply.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/files/atomic_file.h"
#include "core/image/image.h"
#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "method/gaussian/sh4d.h"
#include "method/run/slice3d.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

void CheckExportable(const GaussianModel& model,
                     float time_duration,
                     const fs::path& path,
                     const ExportDisplay* display,
                     const HdrPlyExtension* hdr) {
  const bool log_hdr = model.color_mode != ColorMode::kLdr;
  if (log_hdr && !display) {
    Fail(
        "{}: this model has log-HDR colours; a 3DGS viewer expects display colours (give the "
        "tone mapping to export with)",
        path.string());
  }
  if (log_hdr && display->tone_mapper && !display->tone_mapper->pointwise()) {
    Fail(
        "{}: the '{}' tone mapper works on whole images, not on Gaussians; cannot export "
        "display colours with it",
        path.string(), display->tone_mapper->config().kind);
  }
  if (hdr && !log_hdr)
    Fail("{}: this model has LDR colours (no HDR to export); export it without --hdr", path.string());
  if (hdr && hdr->head && !hdr->head->empty() && hdr->head->offset.size() != model.size() * 3)
    Fail("{}: the HDR head has {} offsets for {} Gaussians", path.string(),
         hdr->head->offset.size(), model.size());
  if (!(time_duration > 0)) Fail("export-ply: time duration must be positive");
  if (model.channels != 3)
    Fail("{}: 3DGS .ply holds RGB; this model has {} channels", path.string(), model.channels);
}

// The column names: the 3DGS layout, then the HDR extension's.
std::vector<std::string> Columns(int rest_per_channel, bool hdr) {
  std::vector<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (int k = 0; k < 3 * rest_per_channel; ++k) names.push_back(fmt::format("f_rest_{}", k));
  names.push_back("opacity");
  for (const char* n : {"scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    names.push_back(n);
  if (!hdr) return names;
  for (int c = 0; c < 3; ++c) names.push_back(fmt::format("f_hdr_dc_{}", c));
  for (int k = 0; k < 3 * rest_per_channel; ++k) names.push_back(fmt::format("f_hdr_rest_{}", k));
  return names;
}

// Gaussian i's row. `sh` holds its colour coefficients at the slice time (FoldedShCoefficients,
// coefficient-major); a log-HDR model's display columns get them too (replaced by the display
// fit, FitDisplaySh) and its extension columns the log-radiance SH, with the HDR head's log
// offset `head_log` added to the DC.
void AppendRow(const GaussianModel& model,
               std::size_t i,
               const Slice3D& slice,
               const double* sh,
               const double* head_log,
               bool hdr,
               std::vector<float>* row) {
  const int functions = model.basis.sh_functions();
  for (int a = 0; a < 3; ++a) row->push_back(static_cast<float>(slice.mean[a]));
  for (int a = 0; a < 3; ++a) row->push_back(0.0f);  // normals (unused by viewers)
  for (int c = 0; c < 3; ++c) row->push_back(static_cast<float>(sh[c]));
  for (int c = 0; c < 3; ++c)
    for (int lm = 1; lm < functions; ++lm)
      row->push_back(static_cast<float>(sh[lm * 3 + c]));
  const double opacity =
      std::clamp(slice.marginal / (1.0 + std::exp(-static_cast<double>(model.opacity_logit[i]))),
                 1e-7, 1 - 1e-7);
  row->push_back(static_cast<float>(std::log(opacity / (1 - opacity))));
  const ScaleRotation axes = PrincipalAxes(slice.cov);
  for (double s : axes.log_scale) row->push_back(static_cast<float>(s));
  for (double q : axes.quaternion) row->push_back(static_cast<float>(q));
  if (!hdr) return;
  for (int c = 0; c < 3; ++c)
    row->push_back(static_cast<float>(sh[c] + head_log[c] / static_cast<double>(kShC0)));
  for (int c = 0; c < 3; ++c)
    for (int lm = 1; lm < functions; ++lm) row->push_back(static_cast<float>(sh[lm * 3 + c]));
}

// Unit directions spread evenly over the sphere (a Fibonacci lattice).
std::vector<Vec3<double>> SphereDirections(int n) {
  std::vector<Vec3<double>> d;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1 - 2 * (k + 0.5) / n, r = std::sqrt(std::max(0.0, 1 - z * z));
    d.emplace_back(r * std::cos(golden * k), r * std::sin(golden * k), z);
  }
  return d;
}

// Display colours of log-HDR values: the run's tone mapper at the frame, or exposure x radiance
// as sRGB.
void ToDisplay(const ExportDisplay& display, const std::vector<float>& log_hdr, std::vector<float>* ldr) {
  ldr->resize(log_hdr.size());
  if (display.tone_mapper) {
    display.tone_mapper->Map(log_hdr.data(), log_hdr.size() / 3, ldr->data());
    return;
  }
  const float exposure = std::exp(display.frame.log_exposure);
  for (std::size_t k = 0; k < ldr->size(); ++k)
    (*ldr)[k] = LinearToSrgb(std::clamp(std::exp(std::min(log_hdr[k], 30.0f)) * exposure, 0.0f, 1.0f));
}

// A log-HDR model's display columns (6 .. 9 + 3 (F-1) of each row, holding its log-HDR SH): its
// view-dependent log-HDR colour at kFitDirections directions through the display map, fitted by
// least squares with SH of the same degree, so a 3DGS viewer shows the tone-mapped colour and
// its view dependence (exact for a view-independent colour, close for a smooth one).
void FitDisplaySh(const ExportDisplay& display, std::size_t width, int sh_degree,
                  std::vector<float>* rows) {
  constexpr int kFitDirections = 64;
  const int f = (sh_degree + 1) * (sh_degree + 1);
  const std::vector<Vec3<double>> dirs = SphereDirections(kFitDirections);
  Eigen::MatrixXd y(kFitDirections, f);
  double basis[16];
  for (int k = 0; k < kFitDirections; ++k) {
    EvalShBasis(dirs[k], sh_degree, basis);
    for (int lm = 0; lm < f; ++lm) y(k, lm) = basis[lm];
  }
  const Eigen::MatrixXd fit = y.completeOrthogonalDecomposition().pseudoInverse();  // f x N
  if (display.tone_mapper) display.tone_mapper->BeginFrame(display.frame);
  const std::size_t n = rows->size() / width;
  auto coef = [&](std::size_t r, int lm, int c) -> float& {
    return (*rows)[r * width + (lm == 0 ? 6 + c : 9 + c * (f - 1) + lm - 1)];
  };
  std::vector<float> log_hdr, ldr;
  constexpr std::size_t kChunk = 4096;  // rows per batch: bounded memory on large models
  for (std::size_t r0 = 0; r0 < n; r0 += kChunk) {
    const std::size_t r1 = std::min(n, r0 + kChunk);
    log_hdr.assign((r1 - r0) * kFitDirections * 3, 0.0f);
    for (std::size_t r = r0; r < r1; ++r)
      for (int k = 0; k < kFitDirections; ++k)
        for (int c = 0; c < 3; ++c) {
          double v = kColorOffset;
          for (int lm = 0; lm < f; ++lm) v += y(k, lm) * coef(r, lm, c);
          log_hdr[((r - r0) * kFitDirections + k) * 3 + c] = static_cast<float>(v);
        }
    ToDisplay(display, log_hdr, &ldr);
    for (std::size_t r = r0; r < r1; ++r)
      for (int c = 0; c < 3; ++c)
        for (int lm = 0; lm < f; ++lm) {
          double v = 0;
          for (int k = 0; k < kFitDirections; ++k)
            v += fit(lm, k) * (ldr[((r - r0) * kFitDirections + k) * 3 + c] - kColorOffset);
          coef(r, lm, c) = static_cast<float>(v);
        }
  }
}

// The header; the HDR extension's comments say what its columns hold and the scene's range.
std::string PlyHeader(std::size_t vertices,
                      const std::vector<std::string>& columns,
                      float time,
                      const HdrPlyExtension* hdr) {
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  if (hdr) {
    header +=
        "comment hdr4d-hdr-ply 1: 3DGS layout plus f_hdr_dc_0..2 and f_hdr_rest_* (channel-major "
        "like f_rest): SH coefficients (3DGS order and constants) of the natural log of linear "
        "radiance, radiance(d) = exp(0.5 + sum_lm Y_lm(d) f_hdr_lm), d the unit direction from the "
        "camera centre to the mean; f_dc/f_rest are display colours (the tone-mapped colour "
        "fitted with SH over 64 directions)\n";
    header += fmt::format("comment hdr4d-time {} (slice: temporal colour and marginal folded in)\n",
                          time);
    header += fmt::format(
        "comment hdr4d-exposure-range {} {} (seconds: the training images' shortest and longest; "
        "an LDR view at exposure e sees radiance x e)\n",
        hdr->exposure_min, hdr->exposure_max);
    const std::vector<float>& b = hdr->background_log_radiance;
    if (b.size() == 3) {
      header += fmt::format(
          "comment hdr4d-background-log-radiance {} {} {} (behind every Gaussian; absent: black)\n",
          b[0], b[1], b[2]);
    }
  }
  header += fmt::format("element vertex {}\n", vertices);
  for (const std::string& name : columns) header += fmt::format("property float {}\n", name);
  header += "end_header\n";
  return header;
}

}  // namespace

std::size_t ExportSlicePly(const GaussianModel& model,
                           float time,
                           float time_duration,
                           const fs::path& path,
                           const ExportDisplay* display,
                           const HdrPlyExtension* hdr) {
  CheckExportable(model, time_duration, path, display, hdr);
  const bool log_hdr = model.color_mode != ColorMode::kLdr;
  const int rest_per_channel = model.basis.sh_functions() - 1;
  const std::vector<std::string> columns = Columns(rest_per_channel, hdr != nullptr);
  const HdrHead* head = hdr && hdr->head && !hdr->head->empty() ? hdr->head : nullptr;
  std::vector<float> rows;
  std::size_t written = 0;
  double sh[16 * 3];
  for (std::size_t i = 0; i < model.size(); ++i) {
    const std::optional<Slice3D> slice = SliceGaussian(model, i, time);
    if (!slice) continue;
    FoldedShCoefficients(model, i, time, time_duration, sh);
    double head_log[3] = {0, 0, 0};
    for (int c = 0; head && c < 3; ++c) head_log[c] = head->offset[i * 3 + c] + head->log_scale;
    AppendRow(model, i, *slice, sh, head_log, hdr != nullptr, &rows);
    ++written;
  }
  if (log_hdr && written > 0) FitDisplaySh(*display, columns.size(), model.basis.max_sh_degree, &rows);
  // Background: the HDR head's offsets and factor apply to the backdrop's HDR as well.
  HdrPlyExtension stated = hdr ? *hdr : HdrPlyExtension{};
  if (hdr && head && stated.background_log_radiance.size() == 3) {
    for (int c = 0; c < 3; ++c)
      stated.background_log_radiance[c] +=
          head->log_scale + (head->background.size() == 3 ? head->background[c] : 0.0f);
  }
  const std::string header = PlyHeader(written, columns, time, hdr ? &stated : nullptr);
  WriteFileAtomic(path, [&](std::ostream& out) {
    out << header;
    out.write(reinterpret_cast<const char*>(rows.data()),
              static_cast<std::streamsize>(rows.size() * sizeof(float)));
  });
  return written;
}

}  // namespace hdr4d::method
