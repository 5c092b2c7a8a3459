#include "method/run/gaussian_scene.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/staged_folder.h"
#include "method/gaussian/constants.h"
#include "method/render/frame_render.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

void GaussianSceneOptions::Validate() const {
  if (size < 16 || size > 2048) Fail("gaussian scene: size {} must be within 16..2048", size);
  if (num_gaussians < 1) Fail("gaussian scene: need at least one Gaussian");
  if (num_cameras < 4) Fail("gaussian scene: need at least 4 cameras (every 4th is held out)");
  if (num_timestamps < 2) Fail("gaussian scene: need at least 2 timestamps");
  if (sh_degree < 0 || sh_degree > 3) Fail("gaussian scene: SH degree {} must be within 0..3", sh_degree);
}

GaussianModel MakeGaussianSceneModel(const GaussianSceneOptions& options) {
  options.Validate();
  std::mt19937_64 rng(options.seed);
  auto u = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
  GaussianModel m;
  m.temporal = true;
  m.basis.max_sh_degree = options.sh_degree;
  m.basis.max_time_degree = 0;
  m.Resize(options.num_gaussians);
  for (int i = 0; i < options.num_gaussians; ++i) {
    for (int a = 0; a < 3; ++a) m.xyz[i * 3 + a] = u(-0.8f, 0.8f);
    m.t[i] = u(0.2f, 0.8f);
    for (int a = 0; a < 3; ++a) m.log_scales[i * 4 + a] = std::log(u(0.06f, 0.22f));
    m.log_scales[i * 4 + 3] = std::log(u(0.8f, 1.5f));  // long-lived: visible over most of [0,1]
    // A random 3D rotation in q_l, and a small space-time tilt in q_r: the slice's mean then
    // moves linearly with t (velocity Sigma_xt / Sigma_tt) while the shape turns.
    for (int a = 0; a < 4; ++a) m.rot_left[i * 4 + a] = u(-1.0f, 1.0f);
    m.rot_right[i * 4 + 0] = 1.0f;
    for (int a = 1; a < 4; ++a) m.rot_right[i * 4 + a] = u(-0.15f, 0.15f);
    m.opacity_logit[i] = u(0.5f, 3.0f);
    for (int c = 0; c < 3; ++c) m.color_dc[i * 3 + c] = (u(0.1f, 0.95f) - kColorOffset) / kShC0;
    // |Y_lm| is about 0.5 at degree 1: coefficients of +-0.6 swing a colour by about +-0.3.
    for (std::size_t f = 0; f < m.rest_stride(); ++f) m.color_rest[i * m.rest_stride() + f] = u(-0.6f, 0.6f);
  }
  return m;
}

Dataset MakeGaussianScene(const GaussianSceneOptions& options, const fs::path& final_root) {
  const GaussianModel model = MakeGaussianSceneModel(options);
  // Built beside its place and moved there when complete (core/files/staged_folder.h).
  StagedFolder staged(final_root);
  const fs::path& root = staged.path();
  constexpr double kFovX = 0.7;
  const PinholeIntrinsics intrinsics =
      PinholeIntrinsics::FromFovX(kFovX, options.size, options.size);
  Dataset dataset;
  dataset.root = root;
  dataset.layout = "dnerf";
  dataset.camera_angle_x = kFovX;
  RenderOptions render;
  render.sh_degree = options.sh_degree;
  render.time_degree = 0;
  render.background = {0, 0, 0};
  render.backend = RasterBackend::kScalar;  // the reference path makes the ground truth
  FrameState state;
  std::vector<float> values(static_cast<std::size_t>(options.size) * options.size * 3);
  for (int c = 0; c < options.num_cameras; ++c) {
    const double angle = 2 * std::numbers::pi * c / options.num_cameras;
    const Eigen::Vector3d eye(4.0 * std::cos(angle), 4.0 * std::sin(angle),
                              1.2 + 0.6 * std::sin(3 * angle));
    const Camera camera{
        intrinsics, LookAtWorldFromCamGl(eye, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ())};
    const bool test = c % 4 == 3;
    for (int k = 0; k < options.num_timestamps; ++k) {
      const double t = static_cast<double>(k) / (options.num_timestamps - 1);
      RenderForward(model, camera, static_cast<float>(t), render, &state, values.data());
      const Image image = DisplayImageFromBuffer(values.data(), options.size, options.size, 3);
      Frame frame;
      frame.split = test ? Split::kTest : Split::kTrain;
      frame.file_path = fmt::format("images/cam{:02d}_t{:03d}.png", c, k);
      frame.image_path = root / frame.file_path;
      frame.time_raw = frame.time = t;
      frame.camera_id = c;
      frame.camera = camera;
      WriteImage(frame.image_path, image);
      std::vector<Frame>& split = test ? dataset.test : dataset.train;
      frame.index = static_cast<int>(split.size());
      split.push_back(frame);
    }
  }
  dataset.time_max_raw = 1.0;
  WriteDataset(dataset, root);
  staged.Commit();
  RebaseDataset(&dataset, final_root);
  return dataset;
}

}  // namespace hdr4d::method
