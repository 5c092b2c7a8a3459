#include "method/run/gaussian_4d_ply.h"

#include <fmt/format.h>

#include <cstring>
#include <string>
#include <vector>

#include "core/files/atomic_file.h"
#include "core/util/error.h"

namespace hdr4d::method {
namespace {

std::vector<std::string> Columns(const GaussianModel& model, bool head) {
  std::vector<std::string> names = {"x", "y", "z", "t"};
  for (int a = 0; a < 4; ++a) names.push_back(fmt::format("scale_{}", a));
  for (int a = 0; a < 4; ++a) names.push_back(fmt::format("rot_{}", a));
  for (int a = 0; a < 4; ++a) names.push_back(fmt::format("rotr_{}", a));
  names.push_back("opacity");
  for (int c = 0; c < model.channels; ++c) names.push_back(fmt::format("f_dc_{}", c));
  const int rest = model.basis.coefficients() - 1;
  for (int k = 0; k < rest * model.channels; ++k) names.push_back(fmt::format("f_rest_{}", k));
  for (int c = 0; head && c < 3; ++c) names.push_back(fmt::format("hdr_offset_{}", c));
  return names;
}

std::string Header(const GaussianModel& model,
                   const Gaussian4dPlyInfo& info,
                   const std::vector<std::string>& columns,
                   bool head) {
  const bool log_hdr = model.color_mode != ColorMode::kLdr;
  std::string h = "ply\nformat binary_little_endian 1.0\n";
  h += "comment hdr4d-4d-ply 1: 4D Gaussians (docs/hdr-ply.md)\n";
  h += fmt::format("comment hdr4d-temporal {}\n", model.temporal ? 1 : 0);
  h += fmt::format(
      "comment hdr4d-colour {} ({})\n", log_hdr ? "log-hdr" : "ldr",
      log_hdr ? "SH x time value + 0.5 is the natural log of linear radiance"
              : "colour = max(SH x time value + 0.5, 0)");
  h += fmt::format("comment hdr4d-basis {} {} (SH degree, time degree)\n",
                   model.basis.max_sh_degree, model.basis.max_time_degree);
  h += fmt::format("comment hdr4d-time-duration {}\n", info.time_duration);
  if (info.exposure_max > 0)
    h += fmt::format("comment hdr4d-exposure-range {} {} (seconds)\n", info.exposure_min,
                     info.exposure_max);
  if (!info.learned_background.empty()) {
    h += "comment hdr4d-learned-background";
    for (float v : info.learned_background) h += fmt::format(" {}", v);
    h += "\n";
  } else {
    h += fmt::format("comment hdr4d-background {}\n", info.background);
  }
  if (head) {
    h += fmt::format("comment hdr4d-hdr-head-log-scale {}\n", info.head->log_scale);
    if (info.head->background.size() == 3)
      h += fmt::format("comment hdr4d-hdr-head-background {} {} {}\n", info.head->background[0],
                       info.head->background[1], info.head->background[2]);
  }
  h += fmt::format("element vertex {}\n", model.size());
  for (const std::string& name : columns) h += fmt::format("property float {}\n", name);
  h += "end_header\n";
  return h;
}

}  // namespace

std::string Gaussian4dPlyBytes(const GaussianModel& model, const Gaussian4dPlyInfo& info) {
  const std::string problem = model.Validate();
  if (!problem.empty()) Fail("4D .ply export: {}", problem);
  const bool head = info.head && !info.head->empty();
  if (head && info.head->offset.size() != model.size() * 3)
    Fail("4D .ply export: the HDR head has {} offsets for {} Gaussians", info.head->offset.size(),
         model.size());
  const std::vector<std::string> columns = Columns(model, head);
  std::string bytes = Header(model, info, columns, head);
  const std::size_t header_size = bytes.size();
  bytes.resize(header_size + model.size() * columns.size() * sizeof(float));
  char* out = bytes.data() + header_size;  // not float-aligned: rows are copied bytewise
  const int channels = model.channels;
  const int rest = model.basis.coefficients() - 1;
  std::vector<float> row;
  for (std::size_t i = 0; i < model.size(); ++i) {
    row.clear();
    for (int a = 0; a < 3; ++a) row.push_back(model.xyz[i * 3 + a]);
    row.push_back(model.t[i]);
    for (int a = 0; a < 4; ++a) row.push_back(model.log_scales[i * 4 + a]);
    for (int a = 0; a < 4; ++a) row.push_back(model.rot_left[i * 4 + a]);
    for (int a = 0; a < 4; ++a) row.push_back(model.rot_right[i * 4 + a]);
    row.push_back(model.opacity_logit[i]);
    for (int c = 0; c < channels; ++c) row.push_back(model.color_dc[i * channels + c]);
    for (int c = 0; c < channels; ++c)
      for (int k = 0; k < rest; ++k)
        row.push_back(model.color_rest[i * model.rest_stride() + k * channels + c]);
    for (int c = 0; head && c < 3; ++c) row.push_back(info.head->offset[i * 3 + c]);
    HDR4D_CHECK(row.size() == columns.size());
    std::memcpy(out + i * columns.size() * sizeof(float), row.data(), row.size() * sizeof(float));
  }
  return bytes;
}

std::size_t ExportGaussian4dPly(const GaussianModel& model,
                                const std::filesystem::path& path,
                                const Gaussian4dPlyInfo& info) {
  const std::string bytes = Gaussian4dPlyBytes(model, info);
  WriteFileAtomic(path, [&](std::ostream& out) {
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  });
  return model.size();
}

}  // namespace hdr4d::method
