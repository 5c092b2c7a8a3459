// --batch-size: the gradient the trainer steps with is the mean of the views' gradients, which
// is the gradient of the batch loss (the mean of the views' losses): checked in double against
// finite differences of that loss through the whole reference render.
#include "method/train/batch_gradients.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "method/render/frame_render.h"

namespace hdr4d::method {
namespace {

GaussianModelT<double> SmallScene(unsigned seed) {
  std::mt19937 rng(seed);
  auto u = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  GaussianModelT<double> m;
  m.temporal = true;
  m.channels = 3;
  m.Resize(8);
  for (int i = 0; i < 8; ++i) {
    for (int a = 0; a < 3; ++a) m.xyz[i * 3 + a] = u(-0.6, 0.6);
    m.t[i] = u(0.4, 0.6);
    for (int a = 0; a < 3; ++a) m.log_scales[i * 4 + a] = std::log(u(0.15, 0.3));
    m.log_scales[i * 4 + 3] = std::log(u(0.3, 0.5));
    for (int a = 0; a < 4; ++a) {
      m.rot_left[i * 4 + a] = u(-1, 1) + (a == 0 ? 1.5 : 0.0);
      m.rot_right[i * 4 + a] = u(-1, 1) + (a == 0 ? 1.5 : 0.0);
    }
    m.opacity_logit[i] = u(-1.2, 0.3);
    for (int c = 0; c < 3; ++c) m.color_dc[i * 3 + c] = u(0.5, 1.5);
  }
  return m;
}

struct View {
  Camera camera;
  double time;
  std::vector<double> weights;  // the view's loss: sum(weights * image)
};

double ViewLoss(const GaussianModelT<double>& m, const View& v, const RenderOptions& options) {
  FrameStateT<double> state;
  std::vector<double> image(v.weights.size());
  RenderForwardReference(m, v.camera, v.time, options, &state, image.data());
  double loss = 0;
  for (std::size_t i = 0; i < image.size(); ++i) loss += image[i] * v.weights[i];
  return loss;
}

GaussianGradientsT<double> ViewGradient(const GaussianModelT<double>& m, const View& v,
                                        const RenderOptions& options) {
  FrameStateT<double> state;
  std::vector<double> image(v.weights.size());
  RenderForwardReference(m, v.camera, v.time, options, &state, image.data());
  GaussianGradientsT<double> g;
  g.ZerosLike(m);
  RenderBackwardReference(m, v.camera, v.time, options, &state, v.weights.data(), &g);
  return g;
}

TEST(BatchGradients, MeanOfTwoViewsIsTheGradientOfTheMeanLoss) {
  GaussianModelT<double> model = SmallScene(5);
  RenderOptions options;
  options.sh_degree = options.time_degree = 0;  // geometry: no view-dependent colour
  options.background = {0.1f, 0.2f, 0.3f};
  std::mt19937 rng(9);
  std::vector<View> views;
  for (const auto& [eye, time] : std::vector<std::pair<Eigen::Vector3d, double>>{
           {{0.3, -4.0, 0.4}, 0.45}, {{-2.5, -3.0, 1.0}, 0.55}}) {
    View v{Camera{PinholeIntrinsics::FromFovX(0.9, 20, 16),
                  LookAtWorldFromCamGl(eye, {0, 0, 0}, Eigen::Vector3d::UnitZ())},
           time, std::vector<double>(20 * 16 * 3)};
    for (double& w : v.weights) w = std::uniform_real_distribution<double>(-1, 1)(rng);
    views.push_back(std::move(v));
  }
  // The trainer's batch: each view's gradient summed, then divided by the batch size.
  GaussianGradientsT<double> batch;
  batch.ZerosLike(model);
  for (const View& v : views) AddGradients(ViewGradient(model, v, options), &batch);
  ScaleGradients(0.5, &batch);
  // Equal to the average of the two single-view gradients...
  const GaussianGradientsT<double> g0 = ViewGradient(model, views[0], options),
                                   g1 = ViewGradient(model, views[1], options);
  for (std::size_t i = 0; i < batch.xyz.size(); ++i)
    EXPECT_DOUBLE_EQ(batch.xyz[i], 0.5 * (g0.xyz[i] + g1.xyz[i]));
  // ...and to finite differences of the batch loss.
  auto batch_loss = [&] {
    return 0.5 * (ViewLoss(model, views[0], options) + ViewLoss(model, views[1], options));
  };
  const double h = 1e-6;
  int checked = 0;
  auto check = [&](std::vector<double>& param, const std::vector<double>& grad, const char* name) {
    for (std::size_t i = 0; i < param.size(); ++i) {
      const double saved = param[i];
      param[i] = saved + h;
      const double plus = batch_loss();
      param[i] = saved - h;
      const double minus = batch_loss();
      param[i] = saved;
      const double fd = (plus - minus) / (2 * h);
      EXPECT_NEAR(grad[i], fd, 2e-5 + 2e-4 * std::abs(fd)) << name << "[" << i << "]";
      ++checked;
    }
  };
  check(model.xyz, batch.xyz, "xyz");
  check(model.t, batch.t, "t");
  check(model.opacity_logit, batch.opacity_logit, "opacity");
  check(model.color_dc, batch.color_dc, "color_dc");
  EXPECT_GT(checked, 50);
}

}  // namespace
}  // namespace hdr4d::method
