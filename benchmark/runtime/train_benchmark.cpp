// Whole-pipeline speed of the 4DGS engine: one frame's preprocess, forward render, backward,
// the loss, the Adam step and a full training iteration, on random 4D Gaussians filling the view
// (Gaussian size chosen so that about 35 contribute per pixel at 200x200 with 20k, as the
// target in BENCHMARKS.md assumes). Args: image size, Gaussians (thousands).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "core/parallel.h"
#include "method/optim/adam.h"
#include "method/optim/densify.h"
#include "method/optim/fused_adam_step.h"
#include "method/render/frame_render.h"
#include "method/train/loss.h"

namespace hdr4d::method {
namespace {

struct Scene {
  GaussianModel model;
  Camera camera;
  RenderOptions options;
};

Scene MakeScene(int size, int thousands) {
  Scene s;
  const int n = thousands * 1000;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  s.model.Resize(n);
  // Scale so the projected footprints overlap about 35 deep at 200x200 / 20k.
  const float scale = 0.019f * std::sqrt(20000.0f / n);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) s.model.xyz[i * 3 + a] = u(rng);
    s.model.t[i] = 0.5f + 0.3f * u(rng);
    for (int a = 0; a < 3; ++a)
      s.model.log_scales[i * 4 + a] = std::log(scale * (1.0f + 0.5f * u(rng)));
    s.model.log_scales[i * 4 + 3] = std::log(0.5f);
    for (int a = 0; a < 4; ++a) s.model.rot_left[i * 4 + a] = u(rng);
    s.model.opacity_logit[i] = u(rng);
    for (int c = 0; c < 3; ++c) s.model.color_dc[i * 3 + c] = u(rng);
    for (std::size_t k = 0; k < s.model.rest_stride(); ++k)
      s.model.color_rest[i * s.model.rest_stride() + k] = 0.05f * u(rng);
  }
  s.camera = Camera{PinholeIntrinsics::FromFovX(0.9, size, size),
                    LookAtWorldFromCamGl({0, -3.2, 0}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
  s.options.background.assign(3, 0.0f);
  return s;
}

void BM_RenderForward(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  Scene s = MakeScene(size, static_cast<int>(state.range(1)));
  FrameState frame;
  std::vector<float> image(static_cast<std::size_t>(size) * size * 3);
  for (auto _ : state) RenderForward(s.model, s.camera, 0.5f, s.options, &frame, image.data());
  state.counters["visible"] = static_cast<double>(frame.num_visible);
  state.counters["entries"] = static_cast<double>(frame.raster.num_entries());
  // n_contrib: 1 + list position of a pixel's last contributor (an upper bound on blends).
  double walked = 0;
  for (int v : frame.raster.n_contrib) walked += v;
  state.counters["walked_per_px"] = walked / frame.raster.n_contrib.size();
}
BENCHMARK(BM_RenderForward)
    ->Args({200, 20})
    ->Args({800, 100})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_RenderBackward(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  Scene s = MakeScene(size, static_cast<int>(state.range(1)));
  FrameState frame;
  std::vector<float> image(static_cast<std::size_t>(size) * size * 3), dL(image.size(), 1e-3f);
  RenderForward(s.model, s.camera, 0.5f, s.options, &frame, image.data());
  GaussianGradients grads;
  grads.ZerosLike(s.model);
  for (auto _ : state)
    RenderBackward(s.model, s.camera, 0.5f, s.options, &frame, dL.data(), &grads);
}
BENCHMARK(BM_RenderBackward)->Args({200, 20})->Unit(benchmark::kMillisecond)->UseRealTime();

// Forward + loss + backward (which writes every gradient row) + Adam step with the finite check,
// as the trainer runs it: fused into the backward, block by block of Gaussians (AdamRowStep).
void BM_TrainingIteration(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  Scene s = MakeScene(size, static_cast<int>(state.range(1)));
  FrameState frame;
  const std::size_t values = static_cast<std::size_t>(size) * size * 3;
  std::vector<float> image(values);
  std::vector<float> gt(values, 0.3f);
  std::vector<float> dL(values);
  GaussianGradients grads;
  grads.ZerosLike(s.model);
  Adam adam;
  AddModelGroups(s.model, grads, LearningRatesAt(OptimizationOptions{}, 4.0, 1), &adam);
  const std::vector<std::string> groups = adam.GroupNames();
  for (auto _ : state) {
    RenderForward(s.model, s.camera, 0.5f, s.options, &frame, image.data());
    PhotometricLoss(image.data(), gt.data(), size, size, 3, 0.2f, dL.data());
    AdamRowStep step = adam.BeginRowStep(groups, s.model.size());
    RenderBackward(s.model, s.camera, 0.5f, s.options, &frame, dL.data(), &grads,
                   StepModelRows(groups, &step));
    benchmark::DoNotOptimize(step.FirstNonFinite());
  }
}
BENCHMARK(BM_TrainingIteration)->Args({200, 20})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hdr4d::method

namespace hdr4d::method {
namespace {

// What the skips save, at 200x200 with 20k Gaussians, forward + backward of one frame:
//  arg 0 = 0: the 4D model;  1: the same content as a 3D model (static scene, no time axis);
//  2: the 4D model plus 80k more Gaussians that live at other times (culled at p(t) <= 0.05).
void BM_SkipCost(benchmark::State& state) {
  const int mode = static_cast<int>(state.range(0));
  Scene s = MakeScene(200, 20);
  if (mode == 1) {
    s.model.temporal = false;
    s.model.basis.max_time_degree = 0;
    s.model.color_rest.resize(s.model.size() * s.model.rest_stride());
  }
  if (mode == 2) {
    const std::size_t n = s.model.size();
    Scene extra = MakeScene(200, 80);
    for (float& t : extra.model.t) t += 5.0f;  // far from t = 0.5 in time
    auto append = [](std::vector<float>& a, const std::vector<float>& b) {
      a.insert(a.end(), b.begin(), b.end());
    };
    append(s.model.xyz, extra.model.xyz);
    append(s.model.t, extra.model.t);
    append(s.model.log_scales, extra.model.log_scales);
    append(s.model.rot_left, extra.model.rot_left);
    append(s.model.rot_right, extra.model.rot_right);
    append(s.model.opacity_logit, extra.model.opacity_logit);
    append(s.model.color_dc, extra.model.color_dc);
    append(s.model.color_rest, extra.model.color_rest);
    benchmark::DoNotOptimize(n);
  }
  s.options.time_degree = s.model.temporal ? 2 : 0;
  FrameState frame;
  std::vector<float> image(200 * 200 * 3);
  std::vector<float> dL(image.size(), 1e-3f);
  GaussianGradients grads;
  grads.ZerosLike(s.model);
  for (auto _ : state) {
    RenderForward(s.model, s.camera, 0.5f, s.options, &frame, image.data());
    RenderBackward(s.model, s.camera, 0.5f, s.options, &frame, dL.data(), &grads);
  }
  state.counters["gaussians"] = static_cast<double>(s.model.size());
  state.counters["visible"] = static_cast<double>(frame.num_visible);
}
BENCHMARK(BM_SkipCost)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hdr4d::method

namespace hdr4d::method {
namespace {

// Slice + project + colour of every Gaussian (the preprocess), forward and backward.
void BM_Preprocess(benchmark::State& state) {
  const bool backward = state.range(2) != 0;
  Scene s = MakeScene(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  FrameState frame;
  const ViewParams<float> view = ViewParams<float>::FromCamera(s.camera);
  PreprocessForward(s.model, view, 0.5f, s.options, &frame);
  frame.splat_grads.SetZero(s.model.size(), s.model.channels);
  std::fill(frame.splat_grads.mean2d.begin(), frame.splat_grads.mean2d.end(), 1e-3f);
  GaussianGradients grads;
  grads.ZerosLike(s.model);
  for (auto _ : state) {
    if (backward) {
      PreprocessBackward(s.model, view, 0.5f, s.options, frame, &grads);
    } else {
      PreprocessForward(s.model, view, 0.5f, s.options, &frame);
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(s.model.size()));
}
BENCHMARK(BM_Preprocess)
    ->Args({200, 20, 0})
    ->Args({200, 20, 1})
    ->Args({800, 100, 0})
    ->Args({800, 100, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace hdr4d::method
