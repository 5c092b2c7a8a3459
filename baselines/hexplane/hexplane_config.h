// The settings of a HexPlane run, defaulting to the reference's D-NeRF configuration
// (Caoang327/HexPlane config/config.py with config/dnerf_slim.yaml over it: HexPlane_Slim,
// multiply-then-concat fusion, density straight from the planes).
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hdr4d::baselines::hexplane {

// What the appearance MLP outputs and what the loss sees.
enum class ColorModel {
  kLdr,     // HexPlane: sigmoid colour, MSE on the LDR images
  kLogHdr,  // log radiance; HDR = exp; LDR (HDR-HexPlane) = sigmoid(ln radiance + ln exposure + offset)
};

struct HexPlaneConfig {
  std::string method = "hexplane";  // hexplane, hexplane-hdr, hdr-hexplane
  ColorModel color = ColorModel::kLdr;
  bool ldr_loss = true;   // MSE on the LDR images
  bool hdr_loss = false;  // MSE on the mu-law HDR target (hexplane-hdr, hdr-hexplane LDR+HDR)
  float hdr_weight = 1.0f;

  // Grid: voxel counts (the spatial resolution is their cube root over the box) and time cells,
  // from init to final over the upsampling iterations (logarithmic steps).
  std::int64_t voxels_init = 262144, voxels_final = 8000000;
  int time_grid_init = 16, time_grid_final = 24;
  std::vector<int> upsample_at = {3000, 6000, 9000};
  std::vector<int> occupancy_at = {4000, 8000, 10000};
  int reference_iterations = 25000;  // the schedules above are for this run length

  int density_comps = 24, app_comps = 48, app_dim = 27;
  int mlp_hidden = 128, fea_pe = 2, view_pe = 2;
  float init_scale = 0.1f, init_shift = 0.0f;
  float density_shift = -10.0f, distance_scale = 25.0f, step_ratio = 0.5f;
  float occupancy_threshold = 0.001f, weight_threshold = 1e-4f;
  int occupancy_time_samples = 64;
  float tv_density = 1e-4f, tv_app = 1e-4f, tv_time_ratio = 2.0f;
  float l1_density = 0.0f, l1_app = 0.0f;
  float lr_grid = 0.02f, lr_nn = 0.001f, lr_decay_ratio = 0.1f, lr_offset = 0.01f;
  float beta1 = 0.9f, beta2 = 0.99f;
  int batch_rays = 4096;
  int iterations = 25000;
  float box = 1.5f;  // the scene box: the cube center +- box (scene_bounds.h sets both)
  std::array<float, 3> center{0.0f, 0.0f, 0.0f};
  float near = 2.0f, far = 6.0f;
  float background = 0.0f;
  // What a ray sees behind the box: "fixed" (the reference: `background` in every channel),
  // "learned" (one learned colour) or "environment" (a learned function of the view direction);
  // neither learned one depends on time (background_env.h).
  std::string background_model = "fixed";
  std::uint64_t seed = 20220401;

  nlohmann::json ToJson() const;
  // Throws hdr4d::Error naming `file` and the key for a missing or wrong value.
  static HexPlaneConfig FromJson(const nlohmann::json& j, const std::string& file);
  // "" when usable, else what is wrong.
  std::string Validate() const;
  // An iteration of the reference's schedules (upsampling, occupancy) moved to this run length.
  int Scaled(int reference_iteration) const;
};

// The methods of the grid family: hexplane (LDR), hexplane-hdr (HexPlane*, log-HDR colours on
// the HDR ground truth alone), hdr-hexplane (HDR-HexPlane, LDR or LDR+HDR supervision).
const std::vector<std::string>& HexPlaneMethods();
bool IsHexPlaneMethod(const std::string& name);
// The method's preset; supervision "auto" (LDR, plus HDR where the scene has it), "ldr", "hdr"
// or "ldr+hdr". hexplane with "hdr" is HexPlane* (the hexplane-hdr preset and name).
HexPlaneConfig HexPlanePreset(const std::string& method, const std::string& supervision,
                              bool scene_has_hdr);

}  // namespace hdr4d::baselines::hexplane
