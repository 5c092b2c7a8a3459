// Whole-pipeline speed of the 4DGS engine: one frame's preprocess, forward render, backward,
// the loss, the Adam step and a full training iteration, on random 4D Gaussians filling the view
// (Gaussian size chosen so that about 35 contribute per pixel at 200x200 with 20k, as the
// target in docs/history/engine-speed.md assumes). Args: image size, Gaussians (thousands).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "core/util/parallel.h"
#include "method/optim/adam.h"
#include "method/optim/densify.h"
#include "method/optim/fused_adam_step.h"
#include "method/optim/time_order.h"
#include "method/render/frame_render.h"
#include "method/render/hdr_color_stage.h"
#include "method/run/render_split.h"
#include "method/tonemap/dynamic_tone_mapper.h"
#include "method/train/initialise.h"
#include "method/train/hdr_loss.h"
#include "method/train/loss.h"

namespace hdr4d::method {
namespace {

struct Scene {
  GaussianModel model;
  Camera camera;
  RenderOptions options;
};

// Counters of the last frame: visible Gaussians, list entries, and n_contrib (1 + list position
// of a pixel's last contributor: an upper bound on blends) averaged over pixels.
void ReportRasterCounters(const FrameState& frame, benchmark::State* state) {
  state->counters["visible"] = static_cast<double>(frame.num_visible);
  state->counters["entries"] = static_cast<double>(frame.raster.num_entries());
  double walked = 0;
  for (int v : frame.raster.n_contrib) walked += v;
  state->counters["walked_per_px"] = walked / frame.raster.n_contrib.size();
}

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
  ReportRasterCounters(frame, &state);
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

// What `hdr4d render` does for HDR-4DGS at each view: log-HDR colours through the Dynamic Tone
// Mapper's colour stage (radiance bank, context learner, curves per visible Gaussian) and one
// 6-channel blend giving the HDR image and the 3D branch's LDR image together: the "HDR + LDR
// render" of issue 15's 40 fps target. Same random Gaussians as RenderForward, colours read as
// log radiance.
void BM_RenderHdrLdr(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  Scene s = MakeScene(size, static_cast<int>(state.range(1)));
  s.model.color_mode = ColorMode::kLogHdr;
  DynamicToneMapper dtm(ToneMapperConfig{});
  HdrColorStage stage(&dtm, /*map_gaussians=*/true);
  stage.SetFrame({.time_index = 0, .log_exposure = std::log(0.5f)}, /*observe_bank=*/true);
  s.options.color_stage = &stage;
  s.options.background.assign(stage.feature_channels(), 0.0f);
  s.options.backward_follows = state.range(2) != 0;  // 0: as hdr4d render (ViewRenderer)
  FrameState frame;
  std::vector<float> image(static_cast<std::size_t>(size) * size * stage.feature_channels());
  for (auto _ : state) RenderForward(s.model, s.camera, 0.5f, s.options, &frame, image.data());
  ReportRasterCounters(frame, &state);
}
BENCHMARK(BM_RenderHdrLdr)
    ->Args({800, 100, 0})
    ->Args({800, 100, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

// The render call of `hdr4d render --timing` on a trained run, so that a render change can be
// timed on real Gaussians (sizes, overlap, opacities and termination as trained, which random
// clouds do not have) in quiet repetitions rather than in whole commands on a noisy host: the
// run folder in HDR4D_BENCH_RUN (skipped without it), loaded and sorted as the command loads it,
// its first 4 training views per iteration. Args: threads, HDR (1: HDR + LDR, 0: LDR alone).
void BM_TrainedRunRender(benchmark::State& state) {
  const char* folder = std::getenv("HDR4D_BENCH_RUN");
  if (folder == nullptr || *folder == '\0') {
    state.SkipWithError("set HDR4D_BENCH_RUN to a trained run's folder");
    return;
  }
  static const std::unique_ptr<LoadedRun> run = [&] {
    auto loaded = std::make_unique<LoadedRun>(LoadRun(folder));
    OrderForRendering(loaded.get());
    return loaded;
  }();
  const ThreadLimit limit(static_cast<int>(state.range(0)));
  const std::unique_ptr<ViewRenderer> renderer = MakeRunRenderer(*run);
  const std::vector<Frame>& frames = run->dataset.train;
  const std::size_t views = std::min<std::size_t>(4, frames.size());
  std::vector<float> ldr, hdr;
  for (auto _ : state) {
    for (std::size_t k = 0; k < views; ++k) {
      const Frame& f = frames[k];
      renderer->Render(f.camera, static_cast<float>(f.time),
                       RunToneFrame(*run, static_cast<float>(f.time), f.exposure), &ldr,
                       state.range(1) != 0 ? &hdr : nullptr);
    }
  }
  state.counters["views"] = static_cast<double>(views);
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(views), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TrainedRunRender)
    ->Args({1, 1})
    ->Args({2, 1})
    ->Args({2, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

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

// The Gaussians of a real run on the OpenSplat comparison scene (../shared/peers/make_scene.cpp):
// 20k points on the surfaces of six spheres standing on a disc of radius 2.5, initialised as
// `hdr4d train` initialises them (3D model: the scene is static; isotropic scales from the 3
// nearest neighbours, opacity 0.1), seen from the scene's camera ring (distance 5, 35 degrees up,
// focal 214 at 200 px). Unlike MakeScene's random cloud these are larger and overlap along the
// surfaces, and a static scene takes the 3D paths: a real run's iteration, not a random one's.
struct SurfaceScene {
  GaussianModel model;
  Camera camera;
  RenderOptions options;
};

SurfaceScene MakeSurfaceScene(int size, int thousands) {
  struct Sphere {
    Eigen::Vector3f center;
    float radius;
  };
  std::vector<Sphere> spheres = {{{0.0f, 0.0f, 0.6f}, 0.6f}};
  const float radii[5] = {0.32f, 0.42f, 0.36f, 0.46f, 0.38f};
  for (int i = 0; i < 5; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 5.0 + 0.3;
    spheres.push_back({{static_cast<float>(1.45 * std::cos(a)),
                        static_cast<float>(1.45 * std::sin(a)), radii[i]},
                       radii[i]});
  }
  const float disc = 2.5f;
  std::vector<double> area;
  for (const Sphere& sp : spheres) area.push_back(4.0 * std::numbers::pi * sp.radius * sp.radius);
  area.push_back(std::numbers::pi * disc * disc);
  std::mt19937 rng(1);
  std::discrete_distribution<int> pick(area.begin(), area.end());
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  PointCloud cloud;
  for (int k = 0; k < thousands * 1000; ++k) {
    const int object = pick(rng);
    Eigen::Vector3f p;
    if (object < static_cast<int>(spheres.size())) {
      const float z = 2.0f * u(rng) - 1.0f, phi = 2.0f * std::numbers::pi_v<float> * u(rng);
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
      p = spheres[object].center +
          spheres[object].radius * Eigen::Vector3f(r * std::cos(phi), r * std::sin(phi), z);
    } else {
      const float r = disc * std::sqrt(u(rng)), phi = 2.0f * std::numbers::pi_v<float> * u(rng);
      p = Eigen::Vector3f(r * std::cos(phi), r * std::sin(phi), 0.0f);
    }
    for (int a = 0; a < 3; ++a) p[a] += noise(rng);
    cloud.positions.push_back(p);
    cloud.colors.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)));
  }
  InitOptions init;
  init.temporal = false;
  init.basis.max_time_degree = 0;
  SurfaceScene s;
  s.model = InitialiseGaussians(cloud, init);
  const double elevation = 35.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d eye(5.0 * std::cos(elevation), 0.0, 5.0 * std::sin(elevation));
  const double focal = 214.451 * size / 200.0;
  s.camera = Camera{PinholeIntrinsics::FromFovX(2.0 * std::atan(0.5 * size / focal), size, size),
                    LookAtWorldFromCamGl(eye, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
  s.options.background.assign(3, 0.0f);
  s.options.time_degree = 0;
  return s;
}

// One training iteration as TrainingRun::Step does it for the plain LDR model (4dgs) on a static
// scene: forward, the L1 + D-SSIM loss against an 8-bit target converted to float each step (as
// TrainView::ToFloat does), the backward with the fused Adam step.
void BM_TrainingIterationSurface(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  SurfaceScene s = MakeSurfaceScene(size, static_cast<int>(state.range(1)));
  FrameState frame;
  const std::size_t values = static_cast<std::size_t>(size) * size * 3;
  std::vector<float> image(values), gt(values), dL(values);
  std::vector<std::uint8_t> target(values);
  for (std::size_t i = 0; i < values; ++i) target[i] = static_cast<std::uint8_t>((i * 37) % 256);
  GaussianGradients grads;
  grads.ZerosLike(s.model);
  Adam adam;
  AddModelGroups(s.model, grads, LearningRatesAt(OptimizationOptions{}, 4.0, 1), &adam);
  const std::vector<std::string> groups = adam.GroupNames();
  for (auto _ : state) {
    for (std::size_t i = 0; i < values; ++i) gt[i] = target[i] * (1.0f / 255.0f);
    RenderForward(s.model, s.camera, 0.0f, s.options, &frame, image.data());
    PhotometricLoss(image.data(), gt.data(), size, size, 3, 0.2f, dL.data());
    AdamRowStep step = adam.BeginRowStep(groups, s.model.size());
    RenderBackward(s.model, s.camera, 0.0f, s.options, &frame, dL.data(), &grads,
                   StepModelRows(groups, &step));
    benchmark::DoNotOptimize(step.FirstNonFinite());
  }
  ReportRasterCounters(frame, &state);
}
BENCHMARK(BM_TrainingIterationSurface)
    ->Args({200, 20})
    ->Args({64, 20})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Reordering a model of N thousand Gaussians by time (time_order.h) with its Adam moments, as
// the trainer does after every densification: the order's computation and the permutation of
// every buffer. The scene's times are shuffled first, so every row moves (a worst case; after a
// densification the survivors are already in order).
void BM_ReorderByTime(benchmark::State& state) {
  Scene scene = MakeScene(200, static_cast<int>(state.range(0)));
  GaussianModel& m = scene.model;
  GaussianGradients grads;
  grads.ZerosLike(m);
  Adam adam;
  AddModelGroups(m, grads, {1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f}, &adam);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0, 1);
  for (auto _ : state) {
    state.PauseTiming();
    for (float& t : m.t) t = u(rng);
    state.ResumeTiming();
    ReorderGaussians(VisibleTimeOrder(m, 0.0f, 1.0f), &m, &adam, nullptr);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.size()));
}
BENCHMARK(BM_ReorderByTime)->Arg(20)->Arg(320)->Unit(benchmark::kMillisecond)->UseRealTime();

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

namespace hdr4d::method {
namespace {

// The photometric loss (L1 + D-SSIM) and its gradient on a size x size RGB image, as a training
// step calls it once per LDR branch: a smooth prediction against a noisy target in [0, 1].
void BM_PhotometricLoss(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const std::size_t n = static_cast<std::size_t>(size) * size * 3;
  std::vector<float> pred(n), gt(n), grad(n);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t pixel = i / 3;
    const float smooth = 0.5f + 0.4f * std::sin(0.05f * static_cast<float>(pixel % size)) *
                                    std::cos(0.07f * static_cast<float>(pixel / size));
    pred[i] = smooth;
    gt[i] = std::clamp(smooth + 0.1f * (u(rng) - 0.5f), 0.0f, 1.0f);
  }
  for (auto _ : state) {
    const LossResult r =
        PhotometricLoss(pred.data(), gt.data(), size, size, 3, kDefaultLambdaDssim, grad.data());
    benchmark::DoNotOptimize(r.value);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(size) * size);
}
BENCHMARK(BM_PhotometricLoss)->Arg(200)->Arg(400)->Arg(800)->Unit(benchmark::kMillisecond)->UseRealTime();

// The HDR term of a training step (AddHdrTerm: the mu-law of the HDR raster, its L1 + D-SSIM
// against the mu-law target, the gradient back through the mu-law into a 6-channel raster
// gradient) on a size x size view of radiance spanning five decades.
void BM_HdrTerm(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const std::size_t pixels = static_cast<std::size_t>(size) * size;
  std::vector<float> hdr(pixels * 3), target(pixels * 3), grad(pixels * 6, 0.0f);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0, 1);
  for (std::size_t i = 0; i < hdr.size(); ++i) {
    const std::size_t pixel = i / 3;
    const float decades = 2.5f + 2.5f * std::sin(0.05f * static_cast<float>(pixel % size)) *
                                     std::cos(0.07f * static_cast<float>(pixel / size));
    hdr[i] = std::pow(10.0f, decades - 5.0f);
    target[i] = MuLawEncode(hdr[i] * (0.9f + 0.2f * u(rng)));
  }
  SupervisionTerms terms;
  HdrLossScratch scratch;
  for (auto _ : state) {
    const double loss =
        AddHdrTerm(hdr, target.data(), size, size, 6, terms, 1.0, &scratch, grad.data());
    benchmark::DoNotOptimize(loss);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(pixels));
}
BENCHMARK(BM_HdrTerm)->Arg(200)->Arg(800)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hdr4d::method

namespace hdr4d::method {
namespace {

// One Adam step over `floats` parameters with non-zero moments and a zero gradient (what a
// Gaussian outside the view costs), on one thread: 16k floats stay in cache, 32M stream from
// memory. Items are floats.
void BM_AdamStepZeroGradient(benchmark::State& state) {
  const std::size_t floats = static_cast<std::size_t>(state.range(0));
  std::vector<float> p(floats, 0.5f), g(floats, 0.0f), warm(floats, 1e-3f);
  Adam adam;
  adam.AddGroup({.name = "rows", .params = p.data(), .grads = warm.data(), .size = floats, .lr = 1e-3f});
  adam.Step();  // non-zero moments
  adam.SetBuffers("rows", p.data(), g.data(), floats);
  const ThreadLimit one(1);
  for (auto _ : state) adam.Step();
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(floats));
}
BENCHMARK(BM_AdamStepZeroGradient)->Arg(16 << 10)->Arg(32 << 20)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hdr4d::method
