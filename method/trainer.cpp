#include "method/trainer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <numeric>
#include <optional>
#include <random>
#include <set>
#include <sstream>

#include "core/dataset.h"
#include "core/error.h"
#include "core/folder_lock.h"
#include "core/hdr_alignment.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/metrics.h"
#include "core/output_guard.h"
#include "core/parallel.h"
#include "core/ply.h"
#include "core/progress.h"
#include "core/scene_profile.h"
#include "method/adam.h"
#include "method/checkpoint.h"
#include "method/densify.h"
#include "method/fused_step.h"
#include "method/hdr_color_stage.h"
#include "method/hdr_loss.h"
#include "method/loss.h"
#include "method/render.h"
#include "method/resume_check.h"
#include "method/tonemap/radiance_bank.h"
#include "method/train_views.h"
#include "method/view_render.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

std::string TrainOptions::Validate() const {
  if (data.empty()) return "data: no scene folder given";
  if (out.empty()) return "out: no run folder given";
  if (threads < 0) return "threads: must be >= 0";
  if (test_every < 0 || checkpoint_every < 0) return "test_every / checkpoint_every: must be >= 0";
  if (!(max_seconds >= 0 && std::isfinite(max_seconds))) return "max_seconds: must be >= 0";
  if (!(background >= 0 && background <= 1)) return "background: must be within [0, 1]";
  if (std::string p = optimization.Validate(); !p.empty()) return p;
  if (std::string p = hdr.Validate(); !p.empty()) return p;
  if (hdr.tone_mapper && !tone_mapper_factory) return "hdr: a tone mapper needs a factory";
  return "";
}

nlohmann::json TrainOptions::ToJson() const {
  const OptimizationOptions& o = optimization;
  return {
      {"data", fs::absolute(data).string()},
      {"seed", seed},
      {"threads", threads},
      {"test_every", test_every},
      {"checkpoint_every", checkpoint_every},
      {"max_seconds", max_seconds},
      {"background", background},
      {"hdr", hdr.ToJson()},
      {"init",
       {{"num_random_points", init.num_random_points},
        {"random_half_extent", init.random_half_extent},
        {"initial_opacity", init.initial_opacity}}},
      {"optimization",
       {{"iterations", o.iterations},
        {"position_lr_init", o.position_lr_init},
        {"position_lr_final", o.position_lr_final},
        {"position_lr_max_steps", o.position_lr_max_steps},
        {"t_lr_init", o.t_lr_init},
        {"f_dc_lr", o.f_dc_lr},
        {"f_rest_lr", o.f_rest_lr},
        {"opacity_lr", o.opacity_lr},
        {"scaling_lr", o.scaling_lr},
        {"rotation_lr", o.rotation_lr},
        {"adam_eps", o.adam_eps},
        {"lambda_dssim", o.lambda_dssim},
        {"densify_from", o.densify_from},
        {"densify_until", o.densify_until},
        {"densification_interval", o.densification_interval},
        {"densify_grad_threshold", o.densify_grad_threshold},
        {"percent_dense", o.percent_dense},
        {"opacity_reset_interval", o.opacity_reset_interval},
        {"prune_opacity", o.prune_opacity},
        {"sh_increase_interval", o.sh_increase_interval}}},
  };
}

namespace {

constexpr const char* kCheckpointName = "checkpoint.bin";

// NeRF++ normalisation: 1.1 x the largest distance of a training camera from their centroid.
double SceneExtent(const std::vector<TrainView>& views) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const TrainView& v : views) mean += v.camera.Center();
  mean /= static_cast<double>(views.size());
  double radius = 0;
  for (const TrainView& v : views) radius = std::max(radius, (v.camera.Center() - mean).norm());
  return 1.1 * std::max(radius, 1e-3);  // one camera: a tiny extent instead of zero
}

// The training images' size for the densification threshold: the geometric mean of width and
// height of the median view (views of one scene normally share one size).
double ImageSize(const std::vector<TrainView>& views) {
  std::vector<double> sizes;
  for (const TrainView& v : views) sizes.push_back(std::sqrt(double(v.width()) * v.height()));
  if (sizes.empty()) return kReferenceImageSize;
  std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
  return sizes[sizes.size() / 2];
}

// Active colour degrees at an iteration: spatial 0 -> 3 every interval, then temporal 0 -> 2.
std::pair<int, int> ColorDegrees(int iteration, const GaussianModel& model, int interval) {
  const int steps = iteration / interval;
  const int sh = std::min(model.basis.max_sh_degree, steps);
  const int time =
      model.temporal ? std::clamp(steps - model.basis.max_sh_degree, 0, model.basis.max_time_degree)
                     : 0;
  return {sh, time};
}

// Means over the views of the LDR metrics of the final LDR render and, where a view has HDR
// ground truth, of the HDR metrics of the HDR render (PSNR as the mean of per-view values, 3DGS).
nlohmann::json Evaluate(ViewRenderer* renderer, const std::vector<TrainView>& views) {
  nlohmann::json mean = nlohmann::json::object();
  if (views.empty()) return mean;
  std::map<std::string, std::pair<double, int>> sums;
  std::vector<float> ldr, hdr, gt;
  // The pixels some LDR bracket of the same view and time measures (the views sharing an HDR
  // ground truth), for the scale-aligned HDR metrics (core/hdr_alignment.h).
  std::map<std::filesystem::path, std::vector<Image>> brackets;
  for (const TrainView& v : views) {
    if (!v.hdr_path) continue;
    v.ToFloat(&gt);
    brackets[*v.hdr_path].push_back(DisplayImageFromBuffer(gt.data(), v.width(), v.height(), 3));
  }
  std::map<std::filesystem::path, std::vector<std::uint8_t>> measured;
  for (const auto& [path, images] : brackets) measured[path] = MeasurableInBrackets(images);
  for (const TrainView& v : views) {
    const ToneFrame frame{v.time_index, -1, static_cast<float>(std::log(v.exposure))};
    renderer->Render(v.camera, v.time, frame, &ldr, &hdr);
    // Means over the views where a metric is defined, as hdr4d eval does: the log-log slope
    // of a view with no measured pixel (every bracket clipped) is NaN and left out.
    auto add = [&](const MetricList& metrics) {
      for (const auto& [key, value] : metrics) {
        if (!std::isfinite(value)) continue;
        sums[key].first += value;
        sums[key].second += 1;
      }
    };
    if (!ldr.empty()) {
      v.ToFloat(&gt);
      add(LdrMetrics(DisplayImageFromBuffer(ldr.data(), v.width(), v.height(), 3),
                     DisplayImageFromBuffer(gt.data(), v.width(), v.height(), 3)));
    }
    if (!hdr.empty() && v.hdr_path) {
      Image prediction(v.width(), v.height(), 3, Encoding::kLinear);
      std::copy(hdr.begin(), hdr.end(), prediction.data());
      const Image truth = ReadImage(*v.hdr_path);
      add(HdrMetrics(prediction, truth));
      add(AlignedHdrMetrics(prediction, truth, &measured.at(*v.hdr_path)));
    }
  }
  for (const auto& [key, sum] : sums) mean[key] = FiniteOrNull(sum.first / sum.second);
  return mean;
}

// Training state beyond the model and optimiser, for exact resumption.
struct LoopState {
  int iteration = 0;
  std::mt19937_64 rng;
  std::vector<std::uint32_t> order;  // current epoch's view order
  std::size_t next = 0;              // position in `order`
  std::vector<double> loss_curve;
  std::vector<double> psnr_curve;  // training-view PSNR of the final LDR image, per iteration
  nlohmann::json test_curve = nlohmann::json::array();  // {"iteration": i, <metric>: ...}
  double train_seconds = 0;

  std::uint32_t NextView(std::size_t num_views) {
    if (next >= order.size()) {
      order.resize(num_views);
      std::iota(order.begin(), order.end(), 0u);
      std::shuffle(order.begin(), order.end(), rng);
      next = 0;
    }
    return order[next++];
  }

  nlohmann::json ToJson() const {
    std::ostringstream rng_state;
    rng_state << rng;
    return {{"iteration", iteration},
            {"rng", rng_state.str()},
            {"order", order},
            {"next", next},
            {"loss_curve", loss_curve},
            {"psnr_curve", psnr_curve},
            {"test_curve", test_curve},
            {"train_seconds", train_seconds}};
  }
  // The checkpoint's trainer state, checked: values out of range are refused with the file
  // named, never resumed (the checksum catches damage; this catches a writer's mistake).
  void FromJson(const nlohmann::json& j, const fs::path& path, std::size_t num_views) {
    try {
      iteration = j.at("iteration").get<int>();
      std::istringstream rng_state(j.at("rng").get<std::string>());
      rng_state >> rng;
      if (rng_state.fail()) Fail("{}: corrupt checkpoint: unreadable random state", path.string());
      order = j.at("order").get<std::vector<std::uint32_t>>();
      next = j.at("next").get<std::size_t>();
      loss_curve = j.at("loss_curve").get<std::vector<double>>();
      // Checkpoints from before the curves were kept resume with empty ones.
      psnr_curve = j.value("psnr_curve", std::vector<double>{});
      test_curve = j.value("test_curve", nlohmann::json::array());
      train_seconds = j.at("train_seconds").get<double>();
    } catch (const nlohmann::json::exception& e) {
      Fail("{}: corrupt checkpoint trainer state: {}", path.string(), e.what());
    }
    const bool order_ok = std::all_of(order.begin(), order.end(),
                                      [&](std::uint32_t v) { return v < num_views; });
    if (iteration < 0 || !order_ok || next > order.size() || !std::isfinite(train_seconds) ||
        train_seconds < 0 || loss_curve.size() > static_cast<std::size_t>(iteration)) {
      Fail("{}: corrupt checkpoint: trainer state out of range (iteration {}, view order of {} "
           "for {} views, next {}, {} s)",
           path.string(), iteration, order.size(), num_views, next, train_seconds);
    }
  }
};

// Means over at most `blocks` equal runs of consecutive iterations, so results.json stays small
// at any length: {"iteration": last iteration of each block, <name>: mean, ...}.
nlohmann::json CurveBlocks(const std::vector<double>& loss, const std::vector<double>& psnr,
                           int blocks) {
  nlohmann::json curve = {{"iteration", nlohmann::json::array()},
                          {"loss", nlohmann::json::array()},
                          {"train_psnr", nlohmann::json::array()}};
  const std::size_t n = loss.size();
  const std::size_t size = std::max<std::size_t>(1, (n + blocks - 1) / blocks);
  for (std::size_t b = 0; b < n; b += size) {
    const std::size_t e = std::min(n, b + size);
    double l = 0, p = 0;
    for (std::size_t i = b; i < e; ++i) l += loss[i];
    curve["iteration"].push_back(e);
    curve["loss"].push_back(FiniteOrNull(l / (e - b)));
    if (psnr.size() == n) {
      for (std::size_t i = b; i < e; ++i) p += psnr[i];
      curve["train_psnr"].push_back(FiniteOrNull(p / (e - b)));
    }
  }
  return curve;
}

// Removes `folder` when the scope ends by an exception and `made` says this run created it
// and nothing but the run lock is in it.
class RemoveIfFailedEmpty {
 public:
  RemoveIfFailedEmpty(fs::path folder, bool made)
      : folder_(std::move(folder)), made_(made), exceptions_(std::uncaught_exceptions()) {}
  ~RemoveIfFailedEmpty() {
    if (!made_ || std::uncaught_exceptions() == exceptions_) return;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder_, ec)) {
      if (entry.path().filename() != FolderLock::kFileName) return;
    }
    if (!ec) fs::remove_all(folder_, ec);
  }
  RemoveIfFailedEmpty(const RemoveIfFailedEmpty&) = delete;
  RemoveIfFailedEmpty& operator=(const RemoveIfFailedEmpty&) = delete;

 private:
  fs::path folder_;
  bool made_;
  int exceptions_;
};

}  // namespace

int DistinctTimes(const Dataset& dataset) {
  std::set<double> times;
  for (const Frame* f : dataset.AllFrames()) times.insert(f->time);
  return std::max<int>(1, static_cast<int>(times.size()));
}

TrainSummary Train(const TrainOptions& options) {
  if (std::string problem = options.Validate(); !problem.empty()) Fail("train: {}", problem);
  const ThreadLimit thread_limit(options.threads);

  const Dataset dataset = LoadDataset(options.data, {.image_check = ImageCheck::kHeaders});
  const SceneProfile profile = ProfileScene(dataset);
  const HdrTrainingOptions& hdr_options = options.hdr;
  const bool hdr_colors = hdr_options.color_mode == ColorMode::kLogHdr;
  const float background[3] = {options.background, options.background, options.background};
  std::vector<TrainView> train_views =
      LoadViews(dataset, Split::kTrain, background, /*load_hdr=*/hdr_colors);
  std::vector<TrainView> test_views = LoadViews(dataset, Split::kTest, background);
  const int num_times = DistinctTimes(dataset);
  for (auto* views : {&train_views, &test_views}) {
    for (TrainView& v : *views) v.time_index = RadianceBank::TimeIndex(v.time, num_times);
  }
  const bool train_hdr = std::any_of(train_views.begin(), train_views.end(),
                                     [](const TrainView& v) { return !v.hdr_mu.empty(); });
  const double extent = SceneExtent(train_views);
  // A resumed run keeps the configuration it was started with: read it before anything else.
  std::optional<nlohmann::json> saved_config;
  OptimizationOptions requested = options.optimization;
  if (options.resume) {
    saved_config = ReadSavedRunConfig(options.out);
    KeepSavedSchedules(*saved_config, &requested);
  }
  // Schedules for this run's length and image size (an explicit value stays as it is).
  const OptimizationOptions opt = requested.Resolved(ImageSize(train_views));
  const bool temporal = profile.dynamic && !hdr_options.force_static;
  spdlog::info("train: {} train / {} test views, extent {:.3f}, {}, method {}", train_views.size(),
               test_views.size(), extent, temporal ? "dynamic" : "static (no time axis)",
               hdr_options.method);

  std::unique_ptr<ToneMapper> tone_mapper;
  if (hdr_options.tone_mapper) {
    ToneMapperConfig tc = *hdr_options.tone_mapper;
    tc.num_times = num_times;
    tc.num_images = static_cast<int>(train_views.size());
    tc.seed = options.seed;
    tone_mapper = options.tone_mapper_factory(tc);
  }
  const ResolvedHdrTraining resolved =
      ResolveHdrTraining(hdr_options, train_hdr, !tone_mapper || tone_mapper->pointwise());
  TrainOptions recorded = options;  // the schedules as resolved for this run
  recorded.optimization = opt;
  nlohmann::json config = recorded.ToJson();
  config["scene_extent"] = extent;
  config["profile"] = profile.ToJson();
  config["num_times"] = num_times;
  config["resolved"] = resolved.ToJson();
  if (tone_mapper) config["tone_mapper"] = tone_mapper->config().ToJson();
  if (saved_config) RequireSameConfig(*saved_config, config, options.out / "config.json");

  // One writer per run folder; a folder this run made and left with nothing in it on failure
  // is removed again, so a failed start leaves nothing a later command trips over.
  CheckOutputFolder(options.out);  // before the folder or anything in it is made
  std::error_code ec;
  const bool made_folder = !fs::exists(options.out, ec);
  fs::create_directories(options.out, ec);
  if (ec) Fail("{}: cannot create the run folder: {}", options.out.string(), ec.message());
  const RemoveIfFailedEmpty cleanup(options.out, made_folder);
  const FolderLock lock(options.out, "hdr4d train --out " + options.out.string());
  const fs::path checkpoint_path = options.out / kCheckpointName;

  GaussianModel model;
  Adam adam(AdamOptions{.eps = opt.adam_eps});
  DensifyStats stats;
  LoopState loop;
  loop.rng.seed(options.seed);
  if (options.resume) {
    Checkpoint c = LoadCheckpoint(checkpoint_path);
    model = std::move(c.model);
    std::istringstream adam_state(c.adam_state);
    adam.Load(adam_state, checkpoint_path.string());
    loop.FromJson(c.trainer, checkpoint_path, train_views.size());
    if (c.extra_floats.size() != 3)
      Fail("{}: checkpoint has no densification statistics", checkpoint_path.string());
    stats.grad_accum = std::move(c.extra_floats[0]);
    stats.denom = std::move(c.extra_floats[1]);
    stats.max_radii = std::move(c.extra_floats[2]);
    if (model.color_mode != hdr_options.color_mode) {
      Fail("{}: the checkpoint's colour model does not match method '{}'", checkpoint_path.string(),
           hdr_options.method);
    }
    if (tone_mapper) {
      if (c.tone_mapper_state.empty())
        Fail("{}: checkpoint has no tone mapper state", checkpoint_path.string());
      std::istringstream tm_state(c.tone_mapper_state);
      tone_mapper->Load(tm_state, checkpoint_path.string());
    }
    spdlog::info("train: resuming {} at iteration {}", checkpoint_path.string(), loop.iteration);
  } else {
    InitOptions init = options.init;
    init.seed = options.seed;
    init.temporal = temporal;  // a static scene trains without the time axis
    init.color_mode = hdr_options.color_mode;
    std::optional<PointCloud> cloud;
    if (dataset.point_cloud_path) cloud = ReadPly(*dataset.point_cloud_path);
    model = InitialiseGaussians(cloud, init);
    stats.Reset(model.size());
  }
  GaussianGradients grads;
  grads.ZerosLike(model);
  const bool tone_mapper_group = tone_mapper && !tone_mapper->params().empty();
  if (options.resume) {
    BindModelGroups(model, grads, &adam);
    if (tone_mapper_group) {
      adam.SetBuffers(kGroupToneMapper, tone_mapper->params().data(), tone_mapper->grads().data(),
                      tone_mapper->params().size());
    }
  } else {
    AddModelGroups(model, grads, LearningRatesAt(opt, extent, 0), &adam);
    if (tone_mapper_group) {
      adam.AddGroup({.name = kGroupToneMapper,
                     .params = tone_mapper->params().data(),
                     .grads = tone_mapper->grads().data(),
                     .size = tone_mapper->params().size(),
                     .lr = tone_mapper->learning_rate()});
    }
  }
  WriteJsonFile(options.out / "config.json", config);

  RenderOptions render;
  std::optional<HdrColorStage> stage;
  if (resolved.hdr_colors) {
    stage.emplace(tone_mapper.get(), resolved.ldr_gaussian);
    render.color_stage = &*stage;
    render.background.assign(stage->feature_channels(), 0.0f);
    for (int c = 3; c < stage->feature_channels(); ++c) render.background[c] = options.background;
  } else {
    render.background.assign(model.channels, options.background);
  }
  const int raster_channels = static_cast<int>(render.background.size());
  const SupervisionTerms terms{.ldr_gaussian = resolved.ldr_gaussian,
                               .ldr_pixel = resolved.ldr_pixel,
                               .hdr = resolved.hdr,
                               .hdr_weight = hdr_options.hdr_weight,
                               .lambda_dssim = static_cast<float>(opt.lambda_dssim)};
  FrameState state;
  HdrLossScratch scratch;
  std::vector<float> image, gt, hdr_mu, dL_dimage;
  const std::string last_good = checkpoint_path.string();

  auto save = [&]() {
    Checkpoint c;
    c.model = model;
    c.trainer = loop.ToJson();
    c.extra_floats = {stats.grad_accum, stats.denom, stats.max_radii};
    std::ostringstream adam_state;
    adam.Save(adam_state);
    c.adam_state = adam_state.str();
    if (tone_mapper) {
      std::ostringstream tm_state;
      tone_mapper->Save(tm_state);
      c.tone_mapper_state = tm_state.str();
    }
    SaveCheckpoint(checkpoint_path, c);
  };
  auto evaluate = [&]() {
    RenderOptions base = render;
    base.color_stage = nullptr;
    ViewRenderer renderer(model, tone_mapper.get(), resolved, base, options.background);
    return Evaluate(&renderer, test_views);
  };

  Progress progress("train", opt.iterations - loop.iteration, options.progress);
  const auto start = std::chrono::steady_clock::now();
  const double seconds_before = loop.train_seconds;
  double eval_seconds = 0;  // periodic test evaluations: not training time
  auto training_seconds = [&] {
    return seconds_before - eval_seconds +
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  bool stopped_by_time = false;
  while (loop.iteration < opt.iterations) {
    if (options.max_seconds > 0 && training_seconds() >= options.max_seconds) {
      stopped_by_time = true;
      break;
    }
    const int it = ++loop.iteration;
    SetModelLearningRates(LearningRatesAt(opt, extent, it), &adam);
    std::tie(render.sh_degree, render.time_degree) =
        ColorDegrees(it, model, opt.sh_increase_interval);

    const TrainView& view = train_views[loop.NextView(train_views.size())];
    const std::size_t pixels = static_cast<std::size_t>(view.width()) * view.height();
    image.resize(pixels * raster_channels);
    dL_dimage.resize(pixels * raster_channels);
    view.ToFloat(&gt);
    double loss_value = 0;
    const float* ldr_out = nullptr;  // the final LDR image of this view, for the PSNR shown
    if (!resolved.hdr_colors) {
      RenderForward(model, view.camera, view.time, render, &state, image.data());
      loss_value = PhotometricLoss(image.data(), gt.data(), view.width(), view.height(), 3,
                                   static_cast<float>(opt.lambda_dssim), dL_dimage.data())
                       .value;
      ldr_out = image.data();
    } else {
      if (tone_mapper) tone_mapper->ZeroGrad();
      stage->SetFrame(
          {view.time_index, view.image_index, static_cast<float>(std::log(view.exposure))},
          /*observe_bank=*/true);
      RenderForward(model, view.camera, view.time, render, &state, image.data());
      const float* mu = nullptr;
      if (!view.hdr_mu.empty()) {
        view.HdrMuToFloat(&hdr_mu);
        mu = hdr_mu.data();
      }
      loss_value = HdrFrameLoss(image.data(), raster_channels, view.width(), view.height(),
                                gt.data(), mu, tone_mapper.get(), terms, &scratch, dL_dimage.data())
                       .total;
      // The loss already made the final LDR image: the 2D branch for whole-image mappers,
      // else the clamped 3D branch (none under HDR-only supervision).
      if (resolved.final_ldr_from_pixels && terms.ldr_pixel) {
        ldr_out = scratch.pixel_ldr.data();
      } else if (terms.ldr_gaussian) {
        ldr_out = scratch.ldr.data();
      }
    }
    if (!std::isfinite(loss_value)) {
      Fail("train: iteration {}: the loss is {} (view {}); stopped, the last good checkpoint is {}",
           it, loss_value, view.name, last_good);
    }
    // As in the reference, densification replaces every parameter tensor, so no optimiser step
    // happens on that iteration; an opacity reset replaces only the opacity.
    const bool densify =
        it < opt.densify_until && it > opt.densify_from && it % opt.densification_interval == 0;
    const bool reset_opacity = it < opt.densify_until && it % opt.opacity_reset_interval == 0;
    // The model's groups step inside the backward, block by block as their gradient rows are
    // written (AdamRowStep: the same values as StepGroup after it, without reading 13 MB of
    // gradients back from memory). A non-finite gradient stops training below; the state in
    // memory is then dropped and the last checkpoint kept.
    std::vector<std::string> fused;
    if (!densify) {
      for (const char* group : kModelGroups) {
        if (!(reset_opacity && std::string(group) == kGroupOpacity)) fused.emplace_back(group);
      }
    }
    AdamRowStep row_step = adam.BeginRowStep(fused, model.size());
    const GradientRowsDone step_rows = StepModelRows(fused, &row_step);
    RenderBackward(model, view.camera, view.time, render, &state, dL_dimage.data(), &grads,
                   step_rows);
    if (tone_mapper) tone_mapper->EndFrameBackward();
    std::vector<std::string> unchecked;  // the groups the row step did not see
    for (const std::string& group : adam.GroupNames()) {
      if (std::find(fused.begin(), fused.end(), group) == fused.end()) unchecked.push_back(group);
    }
    std::string bad = row_step.FirstNonFinite();
    if (bad.empty()) bad = adam.FirstNonFiniteGradient(unchecked);
    if (!bad.empty()) {
      Fail(
          "train: iteration {}: non-finite gradient in parameter group '{}'; stopped, the last "
          "good checkpoint is {}",
          it, bad, last_good);
    }
    if (it < opt.densify_until)
      AccumulateStats(state.splat_grads.mean2d, state.screen_radius, view.width(), view.height(),
                      &stats);
    loop.loss_curve.push_back(loss_value);

    if (densify) {
      DensifyAndPrune(&model, &grads, &adam, &stats, DensifyParamsAt(opt, extent, it), &loop.rng);
      // The reference's optimiser step after densification skips the replaced tensors (they
      // have no gradient) but still moves the tone mapper, which densification leaves alone.
      if (tone_mapper_group) adam.StepGroup(kGroupToneMapper);
    } else {
      for (const std::string& group : unchecked) {
        if (!(reset_opacity && group == kGroupOpacity)) adam.StepGroup(group);
      }
    }
    if (reset_opacity) ResetOpacity(&model, &adam);

    std::string shown = fmt::format("loss {:.4f}", loss_value);
    if (ldr_out) {
      double squared = 0;
      for (std::size_t i = 0; i < pixels * 3; ++i) {
        const double d = std::clamp(ldr_out[i], 0.0f, 1.0f) - gt[i];
        squared += d * d;
      }
      const double psnr = -10.0 * std::log10(std::max(squared / (pixels * 3), 1e-20));
      loop.psnr_curve.push_back(psnr);
      shown += fmt::format(" psnr {:.2f}", psnr);
    }
    progress.Advance(1, fmt::format("{} N {}", shown, model.size()));
    if (options.test_every > 0 && it % options.test_every == 0 && it < opt.iterations) {
      const auto eval_start = std::chrono::steady_clock::now();
      nlohmann::json m = evaluate();
      spdlog::info("train: iteration {}: test {}", it, m.dump());
      m["iteration"] = it;
      loop.test_curve.push_back(std::move(m));
      eval_seconds +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - eval_start).count();
    }
    if (options.checkpoint_every > 0 && it % options.checkpoint_every == 0) {
      loop.train_seconds = training_seconds();
      save();
    }
  }
  progress.Finish();
  loop.train_seconds = training_seconds();
  save();

  TrainSummary summary;
  summary.stopped_by_time = stopped_by_time;
  summary.test_metrics = evaluate();
  summary.train_seconds = loop.train_seconds;
  summary.iterations = loop.iteration;
  summary.gaussians = model.size();
  summary.loss_curve = loop.loss_curve;
  nlohmann::json results = {
      {"method", hdr_options.method},
      {"test", summary.test_metrics},
      {"train_seconds", summary.train_seconds},
      {"iterations", summary.iterations},
      {"gaussians", summary.gaussians},
      {"test_views", test_views.size()},
      {"final_loss",
       loop.loss_curve.empty() ? nlohmann::json(nullptr) : FiniteOrNull(loop.loss_curve.back())},
      {"stopped_by_time", stopped_by_time},
      {"curve", CurveBlocks(loop.loss_curve, loop.psnr_curve, 256)},
      {"test_curve", loop.test_curve}};
  if (options.test_every > 0) {
    nlohmann::json last = summary.test_metrics;
    last["iteration"] = loop.iteration;
    results["test_curve"].push_back(std::move(last));
  }
  WriteJsonFile(options.out / "results.json", results);
  return summary;
}

}  // namespace hdr4d::method
