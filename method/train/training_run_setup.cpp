// TrainingRun's set-up: the data, the schedules for the run's length and image size, the tone
// mapper, the method and stop a scene gets, and the configuration to record.
#include "method/train/training_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <tuple>

#include "core/dataset/val_split.h"
#include "core/files/json_util.h"
#include "core/util/error.h"
#include "core/util/free_memory.h"
#include "method/tonemap/tone_mapper_registry.h"
#include "method/train/content_views.h"
#include "method/train/correction_cameras.h"
#include "method/train/memory_check.h"
#include "method/train/resume_check.h"

namespace hdr4d::method::training_run {

namespace {

// NeRF++ normalisation: 1.1 x the largest distance of a training camera from their centroid.
// The reference's scene extent: 1.1 x the largest distance of a camera centre from their mean.
// Cameras that share one centre (one fixed camera, a tripod turning) have none, and an extent of
// 1e-3 made densification prune every Gaussian as world-large (stop 94 sweep: 0 Gaussians, exit
// 0); their extent is then the content's, the median distance of the cloud's points from the
// centre (`points` may be null: no cloud, the old floor).
double SceneExtent(const std::vector<TrainView>& views, const std::vector<Eigen::Vector3f>* points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const TrainView& v : views) mean += v.camera.Center();
  mean /= static_cast<double>(views.size());
  double radius = 0;
  for (const TrainView& v : views) radius = std::max(radius, (v.camera.Center() - mean).norm());
  if (points && !points->empty()) {
    std::vector<double> depth;
    depth.reserve(points->size());
    for (const Eigen::Vector3f& p : *points) depth.push_back((p.cast<double>() - mean).norm());
    std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
    const double content = depth[depth.size() / 2];
    if (std::isfinite(content) && radius < 1e-4 * content) radius = content;
  }
  return 1.1 * std::max(radius, 1e-3);
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

// The training pixels of one timestamp: the pixels of the distinct (time, camera) pairs of the
// training views over the number of distinct times (a rig's cameras at one time, each counted
// once whatever its exposures; one frame of a monocular scene; every view of a static scene).
double PixelsPerTime(const std::vector<TrainView>& views) {
  std::set<float> times;
  std::set<std::tuple<float, std::int64_t, std::int64_t, std::int64_t>> shots;
  double pixels = 0;
  for (const TrainView& v : views) {
    times.insert(v.time);
    const Eigen::Vector3d c = v.camera.Center() * 1e6;
    if (shots.emplace(v.time, std::llround(c.x()), std::llround(c.y()), std::llround(c.z())).second)
      pixels += double(v.width()) * v.height();
  }
  return times.empty() ? 0.0 : pixels / double(times.size());
}

}  // namespace

// The data, the schedules for this run's length and image size, the tone mapper and the
// configuration to record (a resumed run must match the one it continues).
void TrainingRun::SetUp() {
  RequireRunFolderNotAScene(options_.out);
  if (options_.resume) CheckGivenAgainstSaved();
  else RequireFreshRunFolder(options_.out, options_.overwrite);  // before the scene is read
  dataset_.emplace(LoadDataset(
      options_.data, {.image_check = ImageCheck::kHeaders,
                      .exposure_unit = ParseExposureUnit(options_.exposure_unit, "train")}));
  data_record_ = RecordDataset(*dataset_);
  if (options_.resume) CheckDataUnchanged();
  if (!options_.resume && dataset_->point_cloud_path) {  // before any image is decoded
    CheckInitialCloudFits(*dataset_->point_cloud_path,
                          ReadPlyVertexCount(*dataset_->point_cloud_path),
                          options_.optimization.max_gaussians, AvailableMemoryBytes());
  }
  profile_ = ProfileScene(*dataset_);
  PickMethodForScene();
  PickStopForScene();
  // A resumed run that turned --no-stop-on-val keeps the growth stop its val curve found.
  if (options_.optimization.grow_on_val && !options_.optimization.stop_on_val && !options_.resume)
    Fail("train: --grow-on-val is decided by the val evaluations of --stop-on-val; add "
         "--iterations auto --stop-on-val (or drop --grow-on-val)");
  // A resumed run may turn --no-stop-on-val to train on; the best is then never taken back.
  if (options_.optimization.keep_best_val && !options_.optimization.stop_on_val &&
      !options_.resume)
    Fail("train: --keep-best-val keeps the best of the val evaluations of --stop-on-val; add "
         "--iterations auto --stop-on-val (or drop --keep-best-val)");
  num_times_ = DistinctTimes(*dataset_);
  if (options_.hdr.tone_mapper) {
    ToneMapperConfig tc = *options_.hdr.tone_mapper;
    tc.num_times = num_times_;
    tc.num_images = static_cast<int>(dataset_->train.size());
    tc.seed = options_.seed;
    tone_mapper_ = MakeToneMapper(tc);
  }
  LoadTrainingViews();
  StartCameraCorrection();
  ResolveSchedules();
  ResolveLearnedBackground();
  RecordConfig();
}

// A resumed run keeps the configuration it was started with: an option given now that differs
// is refused before the scene is read (a paper-size scene takes a minute to load); what only the
// scene resolves is compared once it is (RecordConfig).
void TrainingRun::CheckGivenAgainstSaved() {
  saved_config_ = ReadSavedRunConfig(options_.out);
  nlohmann::json given = options_.ToJson();
  if (AcceptAddedHdrHead(&*saved_config_, given["hdr"])) {
    spdlog::info("train: {} was trained with supervision ldr; it continues as an ldr+hdr run "
                 "with --hdr-head, whose training loop is the same, and fits the HDR head when "
                 "its steps are done",
                 options_.out.string());
  }
  nlohmann::json& o = given["optimization"];
  for (auto it = o.begin(); it != o.end();) {
    // kFollowRunLength (negative) fields and t_lr_init's "as position_lr_init" are resolved
    // with the scene.
    if (it->is_number() && it->get<double>() < 0) it = o.erase(it); else ++it;
  }
  // Log-HDR colours take their own DC rate (OptimizationOptions::Resolved); the method, and
  // with it the colours, is picked with the scene when when_nothing_hdr is set.
  if (options_.when_nothing_hdr) {
    given.erase("hdr");
    o.erase("f_dc_lr");
  } else if (options_.hdr.color_mode == ColorMode::kLogHdr) {
    o["f_dc_lr"] = options_.optimization.f_dc_lr_log_hdr;
  }
  RequireSameGivenConfig(*saved_config_, given, options_.out / "config.json");
}

// A run continues on the data it started with: a training image swapped for another of the same
// size, or the frames reordered, is refused by name (issue 51 §15). Runs from before the record
// have none to compare with.
void TrainingRun::CheckDataUnchanged() {
  const fs::path file = options_.out / kDataRecordName;
  std::error_code ec;
  if (!fs::exists(file, ec)) return;
  const DatasetRecord before = DatasetRecord::FromJson(ReadJsonFile(file), file.string());
  if (const std::string change = DescribeDatasetChange(before, data_record_); !change.empty()) {
    Fail("{}: the dataset changed since the run {} started ({} records it): {}; --resume "
         "continues a run on the data it started with (train a new run, e.g. with --overwrite, "
         "on the changed data)",
         options_.data.string(), options_.out.string(), file.string(), change);
  }
}

// What each view computes, then the training views (with HDR targets where a term uses them)
// and the checked test views, and the scene's extent.
void TrainingRun::LoadTrainingViews() {
  const HdrTrainingOptions& hdr = options_.hdr;
  const float background[3] = {options_.background, options_.background, options_.background};
  // What each view computes is decided before the images are read, so the HDR targets are
  // loaded only when an HDR term uses them (under LDR supervision they would double a
  // paper-size scene's memory and loading time, issue 15).
  resolved_ = ResolveHdrTraining(hdr, profile_.hdr_gt_in_train,
                                 !tone_mapper_ || tone_mapper_->pointwise());
  if (options_.optimization.prune_radiance_share && !resolved_.hdr_colors)
    Fail("train: --prune-radiance-share: this run's Gaussians carry LDR colours, so there is "
         "no radiance to share; drop it, or train a method with HDR colours (hdr4dgs, hdr-gs, "
         "4dgs-hdr)");
  train_views_ = LoadViews(*dataset_, Split::kTrain, background,
                           /*load_hdr=*/resolved_.hdr || resolved_.hdr_head, options_.resolution,
                           hdr.hdr_target);
  // Checked now, read again at each evaluation (train_views.h: not held while training).
  test_views_ = CheckViews(*dataset_, Split::kTest, background, options_.resolution);
  if (options_.optimization.stop_on_val) {
    try {
      val_views_ = CheckViews(*dataset_, Split::kVal, background, options_.resolution);
    } catch (const Error& e) {
      // A val split read only because PickStopForScene chose the stop: say why, and the way out.
      if (!options_.stop_on_val_where_split || options_.resume) throw;
      Fail("{} (the val split is read to decide when to stop, as no run length was given; "
           "--iterations N trains N without it)",
           e.what());
    }
    if (val_views_.empty()) {
      Fail(
          "train: --stop-on-val: the scene {} has no val split (transforms_val.json, or "
          "val_filenames in transforms.json); drop --stop-on-val to stop on the training loss",
          options_.data.string());
    }
  }
  for (auto* views : {&train_views_, &test_views_, &val_views_}) {
    for (TrainView& v : *views) v.time_index = RadianceBank::TimeIndex(v.time, num_times_);
  }
  ReturnFreedMemory();  // the checked test images and the decoding buffers (core/util/free_memory.h)
  extent_ = SceneExtent(train_views_, nullptr);
  if (extent_ <= 1.1e-3 && dataset_->point_cloud_path) {  // the cameras share a centre
    if (!initial_cloud_) initial_cloud_ = ReadPly(*dataset_->point_cloud_path);
    extent_ = SceneExtent(train_views_, &initial_cloud_->positions);
  }
}

// Schedules for this run's length and image size (an explicit value stays as it is; a resumed
// run keeps its own), the Gaussian budget, and whether the model has a time axis.
void TrainingRun::ResolveSchedules() {
  const HdrTrainingOptions& hdr = options_.hdr;
  OptimizationOptions requested = options_.optimization;
  if (saved_config_) KeepSavedSchedules(*saved_config_, &requested);
  temporal_ = profile_.dynamic && !hdr.force_static;
  const double image_size = ImageSize(train_views_);
  opt_ = requested.Resolved(image_size, hdr.color_mode == ColorMode::kLogHdr);
  if (opt_.max_gaussians < 0) {
    // Dynamic: one view's pixels (a rig's cameras film one performance from around it), by its
    // side beyond 200 px, and half as many for one moving camera (neither under --reference).
    const double view_pixels = image_size * image_size;
    std::string rule;
    if (!profile_.dynamic) {
      // Static: one view's pixels per view of distinct content (the cloud's points seen by any
      // camera over those one camera sees), at most 2 x every view's pixels (--reference's).
      const double every_view = PixelsPerTime(train_views_);
      const std::optional<double> content =
          options_.reference ? std::nullopt : StaticContentViews();
      if (content) {
        opt_.max_gaussians = StaticGaussianBudget(view_pixels, *content, every_view);
        rule = fmt::format("static: 1 x one view's pixels, by its side beyond 200 px, x {:.2f} "
                           "views of content, at most 2 x every view's pixels", *content);
      } else {
        opt_.max_gaussians = DefaultGaussianBudget(every_view);
        rule = options_.reference ? "static, --reference: 2 x every view's pixels"
                                  : "static, no point cloud in view: 2 x every view's pixels";
      }
    } else if (options_.reference) {
      opt_.max_gaussians = DefaultGaussianBudget(view_pixels);
      rule = "--reference: 2 x one view's pixels";
    } else if (profile_.multi_view) {
      opt_.max_gaussians = SideScaledGaussianBudget(view_pixels);
      rule = "2 x one view's pixels, by its side beyond 200 px";
    } else {
      opt_.max_gaussians = MonocularGaussianBudget(view_pixels);
      rule = "one moving camera: 1 x one view's pixels, by its side beyond 200 px";
    }
    spdlog::info("train: Gaussian budget {} ({}, at least {})", opt_.max_gaussians, rule,
                 kMinGaussianBudget);
  }
  spdlog::info("train: {} train / {} test views, extent {:.3f}, {}, method {}", train_views_.size(),
               test_views_.size(), extent_, temporal_ ? "dynamic" : "static (no time axis)",
               hdr.method);
}

// How many views' worth of content the training cameras hold (train/content_views.h), from the
// scene's point cloud, which is kept for the model's initialisation; none without a cloud (the
// random points of a cloudless scene are not the scene).
std::optional<double> TrainingRun::StaticContentViews() {
  if (!dataset_->point_cloud_path) return std::nullopt;
  if (!initial_cloud_) initial_cloud_ = ReadPly(*dataset_->point_cloud_path);
  std::vector<Camera> cameras;
  cameras.reserve(train_views_.size());
  for (const TrainView& v : train_views_) cameras.push_back(v.camera);
  return method::ContentViews(initial_cloud_->positions, cameras);
}

// --camera-correction: each view's camera row, and the tone mapper wrapped in the correction.
void TrainingRun::StartCameraCorrection() {
  if (!options_.camera_correction) return;
  if (!tone_mapper_) {
    Fail("train: --camera-correction shifts the tone curve's input, and method '{}' has no tone "
         "mapper",
         options_.hdr.method);
  }
  const CorrectionCameras cameras = FindCorrectionCameras(*dataset_);
  for (auto [views, rows] : {std::pair{&train_views_, &cameras.train},
                             std::pair{&test_views_, &cameras.test},
                             std::pair{&val_views_, &cameras.val}}) {
    for (TrainView& v : *views) v.camera_index = (*rows)[v.image_index];
  }
  auto wrapper = std::make_unique<CameraCorrectedToneMapper>(
      std::move(tone_mapper_), cameras.count,
      CameraCorrectionOptions{.weight = options_.camera_correction_weight,
                              .lr = options_.camera_correction_lr});
  correction_ = wrapper.get();
  tone_mapper_ = std::move(wrapper);
  int held_out = 0;
  for (int row : cameras.test) held_out += row < 0 ? 1 : 0;
  spdlog::info("train: camera correction over {} training cameras ({} of {} test views from "
               "other cameras: uncorrected)",
               cameras.count, held_out, cameras.test.size());
}

// The learned background: as asked, else as the resumed run started (runs from before the
// option recorded nothing and trained without it), else on.
void TrainingRun::ResolveLearnedBackground() {
  if (options_.learn_background) return;
  bool learn = true;
  if (saved_config_) {
    const auto saved = saved_config_->find("learn_background");
    const bool recorded = saved != saved_config_->end();
    if (recorded && !saved->is_boolean())
      Fail("{}: learn_background must be true or false", (options_.out / "config.json").string());
    learn = recorded && saved->get<bool>();
  }
  options_.learn_background = learn;
}

// The configuration to record, with what the scene resolved; a resumed run's must match.
void TrainingRun::RecordConfig() {
  TrainOptions recorded = options_;
  recorded.optimization = opt_;
  config_ = recorded.ToJson();
  config_["scene_extent"] = extent_;
  config_["profile"] = profile_.ToJson();
  config_["num_times"] = num_times_;
  config_["resolved"] = resolved_.ToJson();
  if (tone_mapper_) config_["tone_mapper"] = tone_mapper_->config().ToJson();
  if (correction_) config_["camera_correction_cameras"] = correction_->cameras();
  if (saved_config_) RequireSameConfig(*saved_config_, config_, options_.out / "config.json");
}

// With when_nothing_hdr: a scene whose training frames share one exposure and that has no HDR
// ground truth trains those options instead, with a note (ARCHITECTURE §1).
void TrainingRun::PickMethodForScene() {
  if (!options_.when_nothing_hdr || profile_.num_hdr_frames > 0) return;
  std::set<double> exposures;
  for (const Frame& f : dataset_->train) exposures.insert(f.exposure);
  if (exposures.size() > 1 || options_.hdr.method == options_.when_nothing_hdr->method) return;
  // A warning: shown at the CLI's default verbosity, which hides info.
  scene_notes_.push_back(fmt::format(
      "train: note: every training image has the same exposure and the scene has no HDR ground "
      "truth, so there is no HDR to recover: training the plain LDR model ({}) instead of {} "
      "(ask for --method, --tone-mapper or --supervision to override)",
      options_.when_nothing_hdr->method, options_.hdr.method));
  options_.hdr = *options_.when_nothing_hdr;
}

// With stop_on_val_where_split (no run length asked for): a scene with a val split trains as
// --iterations auto --stop-on-val. Its own held-out views say when more iterations stop paying:
// on D-NeRF lego, mini lego and the demo rig, each with a val split, that run stopped at
// 8000-13000 of 20000 and scored as well or better on the test views
// (docs/history/time-to-quality.md). A scene without one trains the iterations asked for.
void TrainingRun::PickStopForScene() {
  if (!options_.stop_on_val_where_split || options_.resume) return;
  if (dataset_->val.empty()) {
    // One moving camera overfits its few views long before the full run ends; a val split is
    // what lets the default see that (docs/history/time-to-quality.md, "A val split for one
    // moving camera"). hdr4d datagen writes one for such scenes; other sources may not.
    if (profile_.dynamic && !profile_.multi_view &&
        dataset_->train.size() >= static_cast<std::size_t>(kMinTimesForMonocularVal)) {
      scene_notes_.push_back(fmt::format(
          "train: note: one moving camera and no val split: all the iterations run. A val split "
          "(`hdr4d dataset split-val DIR --out NEW --every-time {0}`, or `hdr4d datagen "
          "--val-every {0}`) lets the default stop once held-out views stop improving: on four "
          "datagen scenes of one moving camera it took 0.2-0.8 of the CPU of the full run and "
          "scored better held out on seven of eight runs",
          kMonocularValEvery));
    }
    return;
  }
  OptimizationOptions& o = options_.optimization;
  if (o.stop_window == 0) o.stop_window = OptimizationOptions::kDefaultStopWindow;
  o.stop_on_val = true;
  scene_notes_.push_back(fmt::format(
      "train: note: the scene has a val split ({} views): the run stops once they stop "
      "improving (scored every {} iterations; at most {}), as --iterations auto --stop-on-val "
      "(give --iterations N to train N)",
      dataset_->val.size(), o.stop_window, o.iterations));
}

}  // namespace hdr4d::method::training_run
