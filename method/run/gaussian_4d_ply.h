// A whole 4D model as a .ply: every Gaussian with its time parameters, so a reader can slice it at
// any time (the dynamic export `hdr4d export-ply --dynamic` and the data of `hdr4d view`). Not a
// 3DGS layout (no 3DGS viewer slices in time); its columns and header comments are described in
// docs/hdr-ply.md, and gaussian_ply_reader.h reads it back into the same model.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/render/hdr_head.h"

namespace hdr4d::method {

struct Gaussian4dPlyInfo {
  float time_duration = 1.0f;           // T of the cosine time basis
  double exposure_min = 0, exposure_max = 0;  // seconds, the training images' (0: unknown)
  // The learned background (log radiance for log-HDR colours, else the colour), or empty; a
  // fixed grey background `background` otherwise.
  std::vector<float> learned_background;
  float background = 0.0f;
  const HdrHead* head = nullptr;  // written as hdr_offset_0..2 columns and comments
};

// Columns: x y z t, scale_0..3 (log standard deviations), rot_0..3 (left unit quaternion),
// rotr_0..3 (right), opacity (logit), f_dc_0..C-1, f_rest_* (channel-major: the K-1 coefficients
// of channel 0, then channel 1, ...; k = lm + (Dmax+1)^2 n as in gaussian_model.h), and with an
// HDR head hdr_offset_0..2. Returns the number of Gaussians written.
std::size_t ExportGaussian4dPly(const GaussianModel& model,
                                const std::filesystem::path& path,
                                const Gaussian4dPlyInfo& info);

// The same file's bytes (header and binary body), for embedding.
std::string Gaussian4dPlyBytes(const GaussianModel& model, const Gaussian4dPlyInfo& info);

}  // namespace hdr4d::method
