// The Highway kernels of the fast preprocess (preprocess.h, preprocess_fast.cpp): the float
// preprocess of 4D Gaussians, or of 3D ones (static scenes), vectorised over Gaussians, runtime dispatch over the compiled
// targets. It computes what the reference (preprocess_reference.cpp) computes per Gaussian with
// method/gaussian/'s maths, in the same formulas, so results agree up to float rounding; the
// tests hold the two together on every compiled target. The colour sums over each Gaussian's
// coefficient rows are shared with the reference (preprocess_common.h).
#pragma once

#include <cstdint>

#include "method/render/frame_state.h"

namespace hdr4d::method::detail {

// Gaussians per batch: one AVX-512 vector (two AVX2 vectors, and so on).
inline constexpr int kPreprocessBatch = 16;

struct PreprocessSimdJob {
  // 4D mode (rot_right, t and the 4th scale used) or 3D mode (rotation3d.h's quaternion
  // rotation of rot_left, three scales, no time axis: the model of a static scene).
  bool temporal = true;
  // Model, N rows each.
  const float* xyz = nullptr;  // N x 3
  const float* t = nullptr;
  const float* log_scales = nullptr;  // N x 4
  const float* rot_left = nullptr;    // N x 4
  const float* rot_right = nullptr;   // N x 4
  const float* opacity_logit = nullptr;
  // View.
  float rotation[9] = {};  // row-major cam_from_world rotation
  float translation[3] = {};
  float fx = 0, fy = 0, cx = 0, cy = 0;
  float lim_x = 0, lim_y = 0;  // kFrustumTanMargin x tan(fov / 2)
  float center[3] = {};
  float time = 0, duration = 1;
  // Colour basis.
  int sh_degree = 0, time_degree = 0;
  int functions = 16;     // SH functions per time block of the basis
  int coefficients = 48;  // K, all time blocks
  int used_coefficients = 1;  // those the degrees use (ColorBasis::used_coefficients)
  // Forward outputs (rows of Gaussian i).
  float* mean2d = nullptr;  // N x 2
  float* conic = nullptr;   // N x 3
  float* depth = nullptr;
  float* opacity = nullptr;
  int* radius = nullptr;         // binning radius, 0: culled or unreachable
  int* reach = nullptr;          // N x 2, per-axis binning radii (BinningReach)
  int* screen_radius = nullptr;  // 3-sigma radius, 0: culled
  // Backward inputs.
  const int* radius_in = nullptr;  // the forward's binning radius: > 0 gets gradients
  const float* g_mean2d = nullptr;
  const float* g_conic = nullptr;
  const float* g_opacity = nullptr;
  // Backward outputs, written for the Gaussians of the batch (zeros where radius_in is 0).
  float* d_xyz = nullptr;
  float* d_t = nullptr;
  float* d_log_scales = nullptr;
  float* d_rot_left = nullptr;
  float* d_rot_right = nullptr;
  float* d_opacity_logit = nullptr;
};

// The job of a frame: the model's arrays, the view, the colour basis (preprocess_fast.cpp); the
// caller binds the output arrays.
PreprocessSimdJob MakePreprocessJob(const GaussianModel& model,
                                    const ViewParams<float>& view,
                                    float time,
                                    const RenderOptions& options);

// The Gaussians of [begin, begin + count) that may be visible at the view's time, in order, to
// kept[0..return value); the others are culled (the forward's outputs written: zero radii)
// without their geometry. The same Gaussians as ForwardBatch's own temporal test would cull, or
// fewer (a margin covers rounding). Static (3D) mode keeps them all.
int PreprocessTemporalSurvivors(const PreprocessSimdJob& job,
                                std::int64_t begin,
                                int count,
                                std::int64_t* kept);

// The Gaussians index[0..count), count <= kPreprocessBatch, one per lane (any indices: the
// backward passes only the visible ones). Both also write the colour-basis weights of each
// Gaussian (zeros for the inactive functions) at weights[k * kPreprocessBatch + lane] for the
// coefficients the degrees use, k < used_coefficients; nothing beyond;
// in the forward only for lanes with screen_radius > 0. The backward writes
// the gradients of the Gaussians it is given; the caller zeroes the others'.
void PreprocessForwardSimd(const PreprocessSimdJob& job,
                           const std::int64_t* index,
                           int count,
                           float* weights);
void PreprocessBackwardSimd(const PreprocessSimdJob& job,
                            const std::int64_t* index,
                            int count,
                            float* weights);

}  // namespace hdr4d::method::detail
