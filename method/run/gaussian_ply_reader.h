// Reads back the Gaussian .ply files hdr4d writes (docs/hdr-ply.md): a 3DGS slice (display
// colours), a 3DGS slice with the HDR extension (log-radiance SH), and the 4D layout; and any
// other binary little-endian 3DGS .ply of float columns. The result renders with the project's
// renderer: a slice as a static (3D) model, the 4D file as the model it was written from.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "method/gaussian/gaussian_model.h"

namespace hdr4d::method {

struct GaussianPly {
  GaussianModel model;
  bool four_d = false;  // the 4D layout (gaussian_4d_ply.h)
  // Numbers of each "comment hdr4d-..." line by its key ("hdr4d-time" -> {0.5}), up to the first
  // word that is not a number.
  std::map<std::string, std::vector<double>> comments;
  std::map<std::string, std::string> comment_text;  // the whole text after each key
  std::vector<float> hdr_offset;  // N x 3: the 4D layout's HDR head columns, or empty
};

// A 3DGS slice reads as a static model: with the HDR extension, log-HDR colours from its
// f_hdr_* columns; else LDR colours from f_dc/f_rest (3DGS: colour = max(SH value + 0.5, 0)).
// Throws hdr4d::Error naming the file and the problem (not a binary little-endian .ply of float
// columns, a missing column, a short body).
GaussianPly ReadGaussianPly(const std::filesystem::path& path);

}  // namespace hdr4d::method
