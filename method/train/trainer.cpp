#include "method/train/trainer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/dataset/val_split.h"
#include "core/util/error.h"
#include "core/files/folder_lock.h"
#include "core/util/free_memory.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/util/parallel.h"
#include "core/geometry/ply.h"
#include "core/util/progress.h"
#include "core/dataset/scene_profile.h"
#include "method/gaussian/constants.h"
#include "method/optim/densify.h"
#include "method/optim/model_optimizer.h"
#include "method/optim/time_order.h"
#include "method/render/frame_render.h"
#include "method/render/hdr_color_stage.h"
#include "method/render/learned_background.h"
#include "method/tonemap/camera_correction.h"
#include "method/tonemap/radiance_bank.h"
#include "method/tonemap/tone_mapper_registry.h"
#include "method/train/batch_gradients.h"
#include "method/train/checkpoint.h"
#include "method/train/coarse_images.h"
#include "method/train/correction_cameras.h"
#include "method/train/loss_plateau.h"
#include "method/train/hdr_head_fit.h"
#include "method/train/hdr_loss.h"
#include "method/train/loop_state.h"
#include "method/train/loss.h"
#include "method/train/resume_check.h"
#include "method/train/run_folder.h"
#include "core/dataset/dataset_checksum.h"
#include "method/train/memory_check.h"
#include "method/train/test_evaluation.h"
#include "method/train/tone_curve_watch.h"
#include "method/train/train_options_table.h"
#include "method/train/train_views.h"
#include "method/train/color_bands.h"
#include "method/train/content_views.h"
#include "method/render/view_renderer.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

std::string TrainOptions::Validate() const {
  if (data.empty()) return "data: no scene folder given";
  if (out.empty()) return "out: no run folder given";
  // Every option's range and choices, as the command line states them (train_options_table.h).
  if (std::string p = CheckTrainOptionValues(*this); !p.empty()) return p;
  if (std::string p = optimization.Validate(); !p.empty()) return p;
  if (std::string p = hdr.Validate(); !p.empty()) return p;
  if (reference && optimization.visible_adam)
    return "reference: --reference trains the paper's configuration, which steps Adam densely; "
           "drop --visible-adam (or --reference)";
  if (reference && optimization.color_bands_by_need)
    return "reference: --reference adds every colour band on the paper's schedule; drop "
           "--color-bands-by-need (or --reference)";
  if (reference && optimization.coarse_to_fine > 0)
    return "reference: --reference trains at full size from the start; drop --coarse-to-fine "
           "(or --reference)";
  if (reference && optimization.prune_contribution > 0)
    return "reference: --reference prunes by opacity only; drop --prune-contribution (or "
           "--reference)";
  if (reference && optimization.clone_opacity_correction.value_or(false))
    return "reference: --reference clones with the source's opacity; drop "
           "--clone-opacity-correction (or --reference)";
  if (reference && hdr.tone_mapper && hdr.tone_mapper->kind == "dtm" &&
      hdr.tone_mapper->unseen_rows != "zero")
    return "reference: --reference reads the radiance bank's unwritten rows as zeros; drop "
           "--unseen-bank-rows (or --reference)";
  if (reference && (optimization.stop_window > 0 || optimization.stop_on_val))
    return "reference: --reference trains every iteration asked for; drop --iterations auto, "
           "--stop-window and --stop-on-val (or --reference)";
  if (reference && optimization.keep_best_val)
    return "reference: --reference ends on its last model; drop --keep-best-val (or --reference)";
  if (reference && optimization.grow_on_val)
    return "reference: --reference grows the model up to --max-gaussians; drop --grow-on-val "
           "(or --reference)";
  return "";
}

// RUN/config.json: the rows of the option table (train_options_table.h).
nlohmann::json TrainOptions::ToJson() const { return RecordTrainOptions(*this); }

TrainOptions TrainOptions::FromJson(const nlohmann::json& j, const std::string& source) {
  TrainOptions o;
  ReadTrainOptionsRecord(j, source, "", &o);
  o.out = fs::path(source).parent_path();  // the run folder the file belongs to
  if (std::string p = o.Validate(); !p.empty()) Fail("{}: {}", source, p);
  return o;
}

int DistinctTimes(const Dataset& dataset) {
  std::set<double> times;
  for (const Frame* f : dataset.AllFrames()) times.insert(f->time);
  return std::max<int>(1, static_cast<int>(times.size()));
}

namespace {

// --prune-contribution's blending-weight statistics in a checkpoint: the extra float section after
// the HDR head's (an empty head section when the run has none).
constexpr std::size_t kMaxWeightSection = kHdrHeadSection + 1;
// --color-bands-by-need: the sums of a colour-band probe under way (empty when none runs).
constexpr std::size_t kColorBandSection = kMaxWeightSection + 1;
constexpr const char* kColorBandsKey = "color_bands";

constexpr const char* kCheckpointName = "checkpoint.bin";
// --keep-best-val: the model of the best val evaluation so far, written when one improves on the
// best and taken back at the stop (RestoreBestValModel); removed once results.json is written.
constexpr const char* kBestValName = "best_val.bin";
// In the trainer state: the live model is the best val evaluation's, taken back at the end.
constexpr const char* kBestValRestoredKey = "best_val_restored";

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

// One training run from set-up to results.json: Train() below reads top to bottom as set-up,
// resume or initialise, the steps, and the final save (docs/ARCHITECTURE.md, "One training
// step"). Members are declared in the order they are made.
class TrainingRun {
 public:
  explicit TrainingRun(TrainOptions options) : options_(std::move(options)) {}

  void SetUp();
  void PickMethodForScene();
  void PickStopForScene();
  // The notes of PickMethodForScene and PickStopForScene, shown once the run has started (a
  // start that fails says only what failed).
  void ShowSceneNotes() const {
    for (const std::string& note : scene_notes_) spdlog::warn("{}", note);
  }
  std::vector<std::string> scene_notes_;
  void OpenRunFolder();
  void ResumeOrInitialise();
  GaussianModel InitialModel();
  // A checkpoint's model, optimiser, statistics, colour bands, tone mapper, camera correction
  // and background into the run (not its loop state); `file` names it in errors.
  void LoadTrainingState(Checkpoint* c, const fs::path& file);
  void RestoreDensifyStats(Checkpoint* c, const fs::path& file);
  void StartColorBands(Checkpoint* c, const fs::path& file);
  void BindOptimizer(bool resumed);
  void PrepareRendering();
  void ReserveForBudget();
  // Iterations left, and (--iterations auto) the loss still improving: the training loss, or
  // with --stop-on-val the val split's.
  bool StepsLeft() const { return loop_.iteration < opt_.iterations && !Stopped(); }
  bool Stopped() const {
    return opt_.stop_on_val ? HeldOutStop().has_value() : Plateau().has_value();
  }
  std::optional<LossPlateau> Plateau() const {
    return FindLossPlateau(loop_.loss_curve, opt_.densify_until, opt_.stop_window,
                           opt_.stop_tolerance);
  }
  std::vector<HeldOutPoint> ValPoints() const;
  std::optional<HeldOutPlateau> HeldOutStop() const;
  // --grow-on-val: the evaluation after which the model grows no further, if there is one yet.
  std::optional<GrowthStop> GrowthStopped() const {
    if (!opt_.grow_on_val) return std::nullopt;
    return FindGrowthStop(ValPoints(), opt_.densify_until, opt_.stop_tolerance);
  }
  void EvaluateValViews(int it);
  // The iteration of the best val evaluation (loss_plateau.h BestHeldOutIndex); nullopt before
  // the first.
  std::optional<int> BestValIteration() const;
  // --keep-best-val, once the val views stopped the run: the model of their best evaluation,
  // when a later one is live (the stop waits kHeldOutPatience evaluations past it). The loop
  // state (the iteration, the curves) stays the last one, so a resume finds the run finished.
  void RestoreBestValModel();
  // The iteration of the live model: the loop's, or the best val evaluation's once taken back.
  int ModelIteration() const {
    return best_val_restored_ ? BestValIteration().value_or(loop_.iteration) : loop_.iteration;
  }
  nlohmann::json StopRecord() const;
  bool OutOfTime() const;
  void Step();
  // --hdr-head: fits the HDR head after the last iteration (unless the checkpoint's head was
  // fitted to this very model).
  void FitHdrHeadIfAsked();
  TrainSummary Finish();
  // A resumed run with no step left, a results.json and its HDR head (if asked) fitted: nothing
  // to do (issue 51 §18); its results are reported as they are, no file is rewritten.
  bool AlreadyFinished() const;
  TrainSummary FinishedSummary() const;

 private:
  // SetUp's stages, in order.
  void CheckGivenAgainstSaved();
  void CheckDataUnchanged();
  void LoadTrainingViews();
  void ResolveSchedules();
  std::optional<double> StaticContentViews();  // a static scene's views of content, for its budget
  void ResolveLearnedBackground();
  void StartCameraCorrection();
  void RecordConfig();
  double ViewLoss(const TrainView& view, int it, const float** ldr_out, std::size_t* pixels);
  double ForwardAndLoss(const TrainView& view, const float** ldr_out);
  // The image the blend's geometry gradient takes for the current view (null: dL/dimage).
  const float* GeometryGradient() const {
    return geometry_split_ ? dL_dgeometry_.data() : nullptr;
  }
  bool DensifiesAt(int it) const;
  void OrderByTime();
  bool ResetsOpacityAt(int it) const;
  std::size_t ActiveRestColumns() const;
  void SetColorDegrees(int it);
  GradientRowsDone WithBandProbe(GradientRowsDone step_rows);
  void EndBandProbe(int it, bool rows_stored);
  void BackwardAndUpdate(const TrainView& view, int it, double loss_value,
                         const std::function<void()>& beside);
  double BatchBackwardAndUpdate(int it, const float** ldr_out, std::size_t* pixels);
  void FinishUpdate(int it, double loss_value);
  double TrainingPsnr(const float* ldr_out, std::size_t pixels) const;
  void ShowProgress(double loss_value, std::optional<double> psnr);
  void EvaluateHeldOut(int it);  // the test curve and the val views, when due
  void CheckpointIfDue(int it);
  std::string FlatToneCurveCheck(int it);
  nlohmann::json EvaluateTestViews(bool with_flip);
  nlohmann::json EvaluateOn(const std::vector<TrainView>& views, bool with_flip);
  ViewRenderer EvalRenderer();
  std::vector<const std::vector<float>*> ExtraFloats() const;
  void Save(const fs::path& file);
  void StartLearnedBackground(const nlohmann::json* trainer, const fs::path& file);
  void ReleaseTrainingState();
  double TrainingSeconds() const;

  TrainOptions options_;  // with the method SetUp picks (when_nothing_hdr)
  std::optional<Dataset> dataset_;
  std::optional<PointCloud> initial_cloud_;  // read by StaticContentViews, else at initialisation
  SceneProfile profile_;
  std::vector<TrainView> train_views_, test_views_;
  std::vector<TrainView> val_views_;  // --stop-on-val only
  int num_times_ = 1;
  double extent_ = 0;
  OptimizationOptions opt_;  // the schedules resolved for this run
  bool temporal_ = false;
  std::optional<nlohmann::json> saved_config_;
  DatasetRecord data_record_;  // RUN/data_checksums.json
  nlohmann::json config_;
  std::unique_ptr<ToneMapper> tone_mapper_;
  // --camera-correction: the wrapper tone_mapper_ holds (camera_correction.h), else null.
  CameraCorrectedToneMapper* correction_ = nullptr;
  ResolvedHdrTraining resolved_;
  // The folder guard is declared before the lock: the lock goes first when a failure unwinds.
  std::optional<CleanUpFailedStart> cleanup_;
  std::optional<FolderLock> lock_;
  fs::path checkpoint_path_;
  GaussianModel model_;
  GaussianGradients grads_;
  GaussianGradients view_grads_;  // --batch-size > 1: one view's gradient before it is summed
  BatchStats batch_stats_;
  std::optional<ModelOptimizer> optimizer_;
  // --color-bands-by-need: which colour bands are on, and the probe of the next one.
  std::optional<ColorBandGate> bands_;
  DensifyStats stats_;
  LoopState loop_;
  RenderOptions render_;
  std::optional<HdrColorStage> stage_;
  std::optional<LearnedBackground> background_;  // --learn-background
  int raster_channels_ = 3;
  SupervisionTerms terms_;
  FrameState state_;
  HdrLossScratch scratch_;
  std::vector<float> image_, gt_, hdr_mu_, dL_dimage_;
  // The current view's camera as rendered: its own, or with the intrinsics of the reduced image
  // when --coarse-to-fine reduces it by coarse_ (coarse_images.h).
  Camera camera_;
  int coarse_ = 1;
  // --no-hdr-geometry: dL/dimage without the HDR term, which the geometry's gradient takes, and
  // whether the current view's loss wrote it.
  std::vector<float> dL_dgeometry_;
  bool geometry_split_ = false;
  // --hdr-head: the head, valid for the model while head_current_ (no step since it was fitted
  // or read).
  HdrHead head_;
  bool head_current_ = false;
  // The live model is the best val evaluation's, taken back at the end (RestoreBestValModel);
  // false again after any step.
  bool best_val_restored_ = false;
  std::optional<Progress> progress_;
  // Shown once, when a tone curve is first found flat (tone_curve_watch.h); results.json lists
  // the end of the run's.
  bool flat_curve_shown_ = false;
  std::chrono::steady_clock::time_point start_;
  double seconds_before_ = 0;
  double eval_seconds_ = 0;  // periodic test evaluations: not training time
};

// The data, the schedules for this run's length and image size, the tone mapper and the
// configuration to record (a resumed run must match the one it continues).
void TrainingRun::SetUp() {
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
  extent_ = SceneExtent(train_views_);
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
  initial_cloud_ = ReadPly(*dataset_->point_cloud_path);
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

// One writer per run folder; a folder this run made and left with nothing in it on failure is
// removed again, so a failed start leaves nothing a later command trips over.
void TrainingRun::OpenRunFolder() {
  CheckOutputFolder(options_.out);  // before the folder or anything in it is made
  std::error_code ec;
  const bool made_folder = !fs::exists(options_.out, ec);
  fs::create_directories(options_.out, ec);
  if (ec) Fail("{}: cannot create the run folder: {}", options_.out.string(), ec.message());
  // The clean-up is armed once the lock is ours: a writer that holds it owns what is there.
  lock_.emplace(options_.out, "hdr4d train --out " + options_.out.string());
  cleanup_.emplace(options_.out, made_folder, /*fresh_run=*/!options_.resume);
  if (!options_.resume) {
    RequireFreshRunFolder(options_.out, options_.overwrite);  // again, now that the lock is held
    if (options_.overwrite) RemovePreviousRun(options_.out);
  }
  checkpoint_path_ = options_.out / kCheckpointName;
}

// The checkpoint's extra float sections: densification statistics, the HDR head, and
// --prune-contribution's blending weights.
void TrainingRun::RestoreDensifyStats(Checkpoint* c, const fs::path& file) {
  if (c->extra_floats.size() < 3)
    Fail("{}: checkpoint has no densification statistics", file.string());
  head_ = ReadHdrHead(*c, model_.size(), file.string());
  head_current_ = !head_.empty();
  stats_.grad_accum = std::move(c->extra_floats[0]);
  stats_.denom = std::move(c->extra_floats[1]);
  stats_.max_radii = std::move(c->extra_floats[2]);
  if (opt_.prune_contribution > 0) {
    if (c->extra_floats.size() <= kMaxWeightSection ||
        c->extra_floats[kMaxWeightSection].size() != model_.size())
      Fail("{}: checkpoint has no blending-weight statistics for --prune-contribution",
           file.string());
    stats_.max_weight = std::move(c->extra_floats[kMaxWeightSection]);
  }
}

// --color-bands-by-need: the bands on and a probe under way, from the checkpoint when resuming.
void TrainingRun::StartColorBands(Checkpoint* c, const fs::path& file) {
  if (!opt_.color_bands_by_need) return;
  // A probe is 100 iterations, or the interval where that is shorter (a short test run).
  const ColorBandGate::Options o{.interval = opt_.sh_increase_interval,
                                 .probe_iterations = std::min(100, opt_.sh_increase_interval),
                                 .min_signal = opt_.color_band_signal};
  bands_.emplace(model_.basis, model_.temporal, model_.channels, o);
  if (!c) return;
  if (!c->trainer.contains(kColorBandsKey))
    Fail("{}: corrupt checkpoint: no colour band state for --color-bands-by-need",
         file.string());
  std::vector<float> sums;
  if (c->extra_floats.size() > kColorBandSection) sums = std::move(c->extra_floats[kColorBandSection]);
  bands_->FromJson(c->trainer[kColorBandsKey], std::move(sums), model_.size(), file.string());
}

// The model, optimiser and loop state from the checkpoint, or a new model from the point cloud
// (or random points); then RUN/config.json.
void TrainingRun::ResumeOrInitialise() {
  optimizer_.emplace(opt_, extent_);
  loop_.rng.seed(options_.seed);
  if (options_.resume) {
    Checkpoint c = LoadCheckpoint(checkpoint_path_);
    loop_.FromJson(c.trainer, checkpoint_path_, train_views_.size());
    LoadTrainingState(&c, checkpoint_path_);
    spdlog::info("train: resuming {} at iteration {}", checkpoint_path_.string(), loop_.iteration);
  } else {
    model_ = InitialModel();
    if (opt_.prune_contribution > 0) stats_.max_weight.assign(model_.size(), 0.0f);
    stats_.Reset(model_.size());
    OrderByTime();  // before the optimiser's groups exist: the model alone
    StartColorBands(nullptr, checkpoint_path_);
    StartLearnedBackground(nullptr, checkpoint_path_);
  }
  BindOptimizer(options_.resume);
  if (AlreadyFinished()) return;
  WriteJsonFile(options_.out / "config.json", config_);
  WriteJsonFile(options_.out / kDataRecordName, data_record_.ToJson());
}

// A new model from the scene's point cloud (or random points), within the budget asked for, its
// log-HDR colours started at the HDR targets' level.
GaussianModel TrainingRun::InitialModel() {
  InitOptions init = options_.init;
  init.seed = options_.seed;
  init.temporal = temporal_;  // a static scene trains without the time axis
  init.color_mode = options_.hdr.color_mode;
  std::optional<PointCloud> cloud = std::move(initial_cloud_);  // read for the budget, or now
  if (!cloud && dataset_->point_cloud_path) cloud = ReadPly(*dataset_->point_cloud_path);
  // A budget asked for caps the initial cloud too (the default one leaves it whole) ...
  const std::int64_t asked = options_.optimization.max_gaussians;
  if (cloud && asked > 0 && cloud->size() > static_cast<std::size_t>(asked)) {
    spdlog::info("train: {} points in {}, subsampled to --max-gaussians {}", cloud->size(),
                 dataset_->point_cloud_path->string(), asked);
    SubsamplePointCloud(&*cloud, static_cast<std::size_t>(asked));
  }
  // ... and the random points that replace a missing or too small cloud.
  const bool random = !cloud || cloud->size() < static_cast<std::size_t>(kMinInitialPoints);
  if (random && asked > 0 && init.num_random_points > asked) {
    spdlog::info("train: {} random initial points, capped at --max-gaussians {}",
                 init.num_random_points, asked);
    init.num_random_points = static_cast<int>(asked);
  }
  GaussianModel model = InitialiseGaussians(cloud, init);
  if (resolved_.hdr && model.color_mode == ColorMode::kLogHdr) {
    if (const auto level =
            MedianLogHdrTarget(train_views_, HdrTargetMu(options_.hdr.hdr_target))) {
      const float shift = ShiftLogColoursToLevel(&model, *level);
      spdlog::info("train: log-HDR colours start at the HDR targets' median {:.3g} (x{:.3g})",
                   std::exp(*level), std::exp(shift));
    }
  }
  return model;
}

void TrainingRun::LoadTrainingState(Checkpoint* c, const fs::path& file) {
  model_ = std::move(c->model);
  optimizer_.emplace(opt_, extent_);
  std::istringstream adam_state(c->adam_state);
  optimizer_->Load(adam_state, file.string());
  RestoreDensifyStats(c, file);
  StartColorBands(c, file);
  if (model_.color_mode != options_.hdr.color_mode) {
    Fail("{}: the checkpoint's colour model does not match method '{}'", file.string(),
         options_.hdr.method);
  }
  if (tone_mapper_) {
    if (c->tone_mapper_state.empty())
      Fail("{}: checkpoint has no tone mapper state", file.string());
    std::istringstream tm_state(c->tone_mapper_state);
    tone_mapper_->Load(tm_state, file.string());
  }
  if (correction_) correction_->FromJson(c->trainer, file.string());
  StartLearnedBackground(&c->trainer, file);
  best_val_restored_ = c->trainer.value(kBestValRestoredKey, false);
}

// The optimiser's groups over the model's (and the background's) buffers: new ones for a new
// model, the loaded state's bound to them for a checkpoint's.
void TrainingRun::BindOptimizer(bool resumed) {
  // At batch size 1 the fused step takes the colour gradient rows straight from the backward,
  // so no colour gradient buffer is kept (~0.6 KB per Gaussian; densify.h, ColourRowsOnly).
  // A batch sums every view's gradient first and needs them all.
  grads_.ZerosLike(model_,
                   /*colour=*/!(opt_.batch_size == 1 && FastPreprocessApplies(model_, render_)));
  if (resumed) {
    optimizer_->BindGroups(model_, grads_, tone_mapper_.get());
    if (background_)
      optimizer_->BindBackgroundGroup(background_->params(), background_->grads(),
                                      checkpoint_path_.string());
  } else {
    optimizer_->AddGroups(model_, grads_, tone_mapper_.get());
    // The rate of a Gaussian's DC colour in colour units (colour = kShC0 x coefficient + ...).
    if (background_)
      optimizer_->AddBackgroundGroup(background_->params(), background_->grads(),
                                     static_cast<float>(opt_.f_dc_lr) * kShC0);
  }
}

bool TrainingRun::AlreadyFinished() const {
  std::error_code ec;
  return options_.resume && !StepsLeft() && (!resolved_.hdr_head || head_current_) &&
         fs::exists(options_.out / "results.json", ec);
}

TrainSummary TrainingRun::FinishedSummary() const {
  const fs::path file = options_.out / "results.json";
  const nlohmann::json results = ReadJsonFile(file);
  if (!results.is_object()) Fail("{}: not a run's results (expected a JSON object)", file.string());
  spdlog::warn("train: {} is finished ({} of {} iterations; {}): nothing to do and nothing "
               "rewritten; give --iterations above {} to train further",
               options_.out.string(), loop_.iteration, opt_.iterations, file.string(),
               loop_.iteration);
  TrainSummary summary;
  summary.test_metrics = results.value("test", nlohmann::json::object());
  summary.train_seconds = loop_.train_seconds;
  summary.iterations = loop_.iteration;
  summary.model_iteration = ModelIteration();
  summary.gaussians = model_.size();
  summary.loss_curve = loop_.loss_curve;
  summary.stopped_by_time = results.value("stopped_by_time", false);
  const std::string reason = results.contains("stopped") && results["stopped"].is_object()
                                 ? results["stopped"].value("reason", "")
                                 : "";
  summary.stopped_flat = reason == "loss_plateau" || reason == "val_plateau";
  return summary;
}

// --learn-background: the values saved in the checkpoint's trainer state when resuming, else
// the start. Log-HDR colours start at the median of the Gaussians' initial log colours (the
// level the colours start at, so the backdrop is neither black nor a glare at the start); LDR
// colours at the grey of --background.
void TrainingRun::StartLearnedBackground(const nlohmann::json* trainer, const fs::path& file) {
  if (!options_.learn_background.value_or(false)) return;
  const bool log_hdr = model_.color_mode == ColorMode::kLogHdr;
  const int channels = LearnedBackgroundChannels(model_);
  std::vector<float> values(channels, options_.background);
  if (trainer) {
    values = ReadLearnedBackground(*trainer, channels, file.string());
  } else if (log_hdr && model_.size() > 0) {
    for (int c = 0; c < channels; ++c) {
      std::vector<float> logs(model_.size());
      for (std::size_t i = 0; i < logs.size(); ++i)
        logs[i] = kShC0 * model_.color_dc[i * channels + c] + kColorOffset;
      std::nth_element(logs.begin(), logs.begin() + logs.size() / 2, logs.end());
      values[c] = logs[logs.size() / 2];
    }
  }
  background_.emplace(std::move(values), log_hdr, tone_mapper_.get());
}

// The render options of the training views (with the HDR colour stage for log-HDR colours),
// the loss terms, and the clock.
// Densification grows the model, its optimiser state and the frame's per-Gaussian buffers up to
// the budget in place: no buffer's old and new copies alive at once (densify.h). Only while
// densifying (a run past it never grows), and only when the budget's parameters and both moments
// fit the machine's memory: a larger budget (a static scene's default counts every view's
// pixels) is never reached, and a reservation beyond memory and swap may be refused.
void TrainingRun::ReserveForBudget() {
  if (opt_.max_gaussians <= 0 || loop_.iteration >= opt_.densify_until) return;
  const std::size_t budget = static_cast<std::size_t>(opt_.max_gaussians);
  std::size_t floats = 0;  // per Gaussian
  for (const char* group : kModelGroups) floats += GroupRowWidth(model_, group);
  if (budget > PhysicalMemoryBytes() / (3 * sizeof(float) * floats)) return;
  const std::size_t rows = std::max(model_.size(), budget);
  ReserveModelRows(model_, grads_, &optimizer_->adam(), &stats_, rows);
  state_.ReserveGaussians(rows, model_.channels, raster_channels_);
}

void TrainingRun::PrepareRendering() {
  if (resolved_.hdr_colors) {
    stage_.emplace(tone_mapper_.get(), resolved_.ldr_gaussian);
    render_.color_stage = &*stage_;
    render_.background.assign(stage_->feature_channels(), 0.0f);
    for (int c = 3; c < stage_->feature_channels(); ++c)
      render_.background[c] = options_.background;
  } else {
    render_.background.assign(model_.channels, options_.background);
  }
  raster_channels_ = static_cast<int>(render_.background.size());
  if (background_) render_.background_source = &*background_;
  ReserveForBudget();
  terms_ = {.ldr_gaussian = resolved_.ldr_gaussian,
            .ldr_pixel = resolved_.ldr_pixel,
            .hdr = resolved_.hdr,
            .hdr_weight = options_.hdr.hdr_weight,
            .lambda_dssim = static_cast<float>(opt_.lambda_dssim),
            .hdr_mu = HdrTargetMu(options_.hdr.hdr_target),
            .hdr_align = options_.hdr.hdr_target == HdrTarget::kAligned,
            .pixel_log_epsilon = resolved_.pixel_log_epsilon,
            .hdr_geometry = options_.hdr.hdr_geometry};
  // A resume with no step left (e.g. to fit an HDR head) shows no empty training bar.
  if (opt_.iterations > loop_.iteration)
    progress_.emplace("train", opt_.iterations - loop_.iteration, options_.progress);
  start_ = std::chrono::steady_clock::now();
  seconds_before_ = loop_.train_seconds;
}

double TrainingRun::TrainingSeconds() const {
  return seconds_before_ - eval_seconds_ +
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool TrainingRun::OutOfTime() const {
  return options_.max_seconds > 0 && TrainingSeconds() >= options_.max_seconds;
}

// One iteration: pick a view (a batch of them with --batch-size), render it, the loss, the
// backward with the fused optimiser step, the periodic held-out evaluation, densification,
// progress and the checkpoint.
void TrainingRun::Step() {
  const int it = ++loop_.iteration;
  head_current_ = false;
  best_val_restored_ = false;
  optimizer_->SetIteration(it);
  if (bands_) bands_->Begin(it, model_.size());
  SetColorDegrees(it);
  render_.track_max_weight = opt_.prune_contribution > 0 && it < opt_.densify_until;
  if (tone_mapper_) tone_mapper_->ZeroGrad();  // a batch adds every view's gradient to it
  if (background_) background_->ZeroGrad();
  if (correction_) correction_->ZeroGrad();
  const float* ldr_out = nullptr;  // the final LDR image of the last view, for the PSNR shown
  std::size_t pixels = 0;
  if (opt_.batch_size == 1) {
    const TrainView& view = train_views_[loop_.NextView(train_views_.size())];
    const double loss_value = ViewLoss(view, it, &ldr_out, &pixels);
    std::optional<double> psnr;
    BackwardAndUpdate(view, it, loss_value, [&] {
      if (ldr_out) psnr = TrainingPsnr(ldr_out, pixels);
    });
    ShowProgress(loss_value, psnr);
  } else {
    const double loss_value = BatchBackwardAndUpdate(it, &ldr_out, &pixels);
    ShowProgress(loss_value, ldr_out ? std::optional(TrainingPsnr(ldr_out, pixels)) : std::nullopt);
  }
  CheckpointIfDue(it);
  if (it % kToneCurveCheckEvery == 0) FlatToneCurveCheck(it);
}

// The view's buffers, its forward and loss; a non-finite loss stops training.
double TrainingRun::ViewLoss(const TrainView& view, int it, const float** ldr_out,
                             std::size_t* pixels) {
  coarse_ = CoarseFactor(it, opt_.coarse_to_fine, view.width(), view.height());
  camera_ = view.camera;
  if (coarse_ > 1) camera_.intrinsics = CoarseIntrinsics(view.camera.intrinsics, coarse_);
  *pixels = static_cast<std::size_t>(camera_.intrinsics.width) * camera_.intrinsics.height;
  image_.resize(*pixels * raster_channels_);
  dL_dimage_.resize(*pixels * raster_channels_);
  // The backward reads this view's forward image for the radiance shares (RenderOptions).
  render_.share_image = opt_.prune_radiance_share ? image_.data() : nullptr;
  view.ToFloat(&gt_);
  BoxReduceInPlace(&gt_, view.width(), view.height(), 3, coarse_);
  const double loss_value = ForwardAndLoss(view, ldr_out);
  if (!std::isfinite(loss_value)) {
    Fail("train: iteration {}: the loss is {} (view {}); stopped, the last good checkpoint is {}",
         it, loss_value, view.name, checkpoint_path_.string());
  }
  return loss_value;
}

// Renders `view` and returns the loss of every supervision term; *ldr_out is the final LDR
// image the loss made (null under HDR-only supervision).
double TrainingRun::ForwardAndLoss(const TrainView& view, const float** ldr_out) {
  geometry_split_ = false;
  const int width = camera_.intrinsics.width, height = camera_.intrinsics.height;
  if (!resolved_.hdr_colors) {
    RenderForward(model_, camera_, view.time, render_, &state_, image_.data());
    *ldr_out = image_.data();
    return PhotometricLoss(image_.data(), gt_.data(), width, height, 3,
                           static_cast<float>(opt_.lambda_dssim), dL_dimage_.data())
        .value;
  }
  stage_->SetFrame({view.time_index, view.image_index, static_cast<float>(std::log(view.exposure)),
                    view.camera_index},
                   /*observe_bank=*/true);
  RenderForward(model_, camera_, view.time, render_, &state_, image_.data());
  const float* mu = nullptr;
  if (!view.hdr_mu.empty()) {
    view.HdrMuToFloat(&hdr_mu_);
    // Reduced as mu values (the log-like target), not as radiance: a coarse step's target only.
    BoxReduceInPlace(&hdr_mu_, view.width(), view.height(), 3, coarse_);
    mu = hdr_mu_.data();
  }
  float* geometry = nullptr;
  if (!terms_.hdr_geometry) {
    dL_dgeometry_.resize(dL_dimage_.size());
    geometry = dL_dgeometry_.data();
  }
  const FrameLoss loss =
      HdrFrameLoss(image_.data(), raster_channels_, width, height, gt_.data(), mu,
                   tone_mapper_.get(), terms_, &scratch_, dL_dimage_.data(), geometry);
  geometry_split_ = loss.geometry_split;
  // The loss already made the final LDR image: the 2D branch for whole-image mappers, else the
  // clamped 3D branch (none under HDR-only supervision).
  if (resolved_.final_ldr_from_pixels && terms_.ldr_pixel) {
    *ldr_out = scratch_.pixel_ldr.data();
  } else if (terms_.ldr_gaussian) {
    *ldr_out = scratch_.ldr.data();
  }
  return loss.total;
}

// A 4D model's Gaussians in the order their time windows open (time_order.h), in the model, the
// optimiser's moments (once registered) and the statistics.
void TrainingRun::OrderByTime() {
  if (!model_.temporal || train_views_.empty()) return;
  const auto [first, last] =
      std::minmax_element(train_views_.begin(), train_views_.end(),
                          [](const TrainView& a, const TrainView& b) { return a.time < b.time; });
  ReorderGaussians(VisibleTimeOrder(model_, first->time, last->time), &model_,
                   optimizer_ ? &optimizer_->adam() : nullptr, &stats_);
}

// As in the reference, densification replaces every parameter tensor, so no optimiser step
// happens on that iteration; an opacity reset replaces only the opacity.
bool TrainingRun::DensifiesAt(int it) const {
  return it < opt_.densify_until && it > opt_.densify_from && it % opt_.densification_interval == 0;
}
bool TrainingRun::ResetsOpacityAt(int it) const {
  return it < opt_.densify_until && it % opt_.opacity_reset_interval == 0;
}

// The leading floats of a colour_rest row that the active colour degrees use: the coefficients
// k = n F + lm with n <= time degree and lm < (sh degree + 1)^2 (row index (k - 1) channels).
// A probe's band is rendered but not stepped (color_bands.h).
std::size_t TrainingRun::ActiveRestColumns() const {
  if (bands_) return bands_->step_columns();
  return RestColumns({render_.sh_degree, render_.time_degree}, model_.basis, model_.channels);
}

// The colour degrees iteration `it` renders with: the reference's schedule, or the bands on and
// the one probed (--color-bands-by-need).
void TrainingRun::SetColorDegrees(int it) {
  BandDegrees d = bands_ ? bands_->render_degrees()
                         : ScheduledDegrees(it, model_.basis, model_.temporal,
                                            opt_.sh_increase_interval);
  render_.sh_degree = d.sh;
  render_.time_degree = d.time;
}

// During a probe the backward's colour rows also go to it, before the optimiser steps them.
// Without a row callback (a batch's or a densifying step's stored gradients) EndBandProbe takes
// them from grads_.
GradientRowsDone TrainingRun::WithBandProbe(GradientRowsDone step_rows) {
  if (!bands_ || !bands_->probing() || !step_rows) return step_rows;
  return [this, step = std::move(step_rows)](std::int64_t b, std::int64_t e,
                                             const GradientRows& rows) {
    bands_->Add(b, e, rows);
    step(b, e, rows);
  };
}

// After the backward and before a densification moves the rows: the probe's stored rows, and
// its decision when it ends.
void TrainingRun::EndBandProbe(int it, bool rows_stored) {
  if (!bands_ || !bands_->probing()) return;
  if (rows_stored && grads_.color_dc.size() == model_.color_dc.size())
    bands_->Add(0, static_cast<std::int64_t>(model_.size()),
                GradientRows{grads_.color_dc.data(), grads_.color_rest.data()});
  if (const std::optional<BandDecision> d = bands_->End(it, DensifiesAt(it))) {
    spdlog::info("train: iteration {}: colour band SH {} time {}: signal {:.3g} (DC {:.3g}) -> {}",
                 it, d->band.sh, d->band.time, d->signal, d->dc_signal,
                 d->switched_on ? "on" : "stays frozen");
  }
}

// The backward with the model's optimiser step fused into it, then FinishUpdate.
// `beside` runs alongside the backward (RunAlongside), which must not write what it reads: the
// progress PSNR, a sequential sum over the image that would otherwise leave a thread idle.
void TrainingRun::BackwardAndUpdate(const TrainView& view, int it, double loss_value,
                                    const std::function<void()>& beside) {
  const GradientRowsDone step_rows = WithBandProbe(
      optimizer_->Begin(DensifiesAt(it), ResetsOpacityAt(it), model_.size(), ActiveRestColumns()));
  // The backward reads the loss's gradient image and the render state, not the final LDR image
  // or the target.
  RunAlongside(beside, [&] {
    RenderBackward(model_, camera_, view.time, render_, &state_, dL_dimage_.data(), &grads_,
                   step_rows, GeometryGradient());
  });
  EndBandProbe(it, /*rows_stored=*/!step_rows);
  if (tone_mapper_) tone_mapper_->EndFrameBackward();
  if (it < opt_.densify_until)
    AccumulateStats(state_.splat_grads.mean2d, state_.screen_radius, camera_.intrinsics.width,
                    camera_.intrinsics.height, &stats_, coarse_);
  if (render_.track_max_weight) AccumulateMaxWeight(state_.splat_grads.max_weight, &stats_);
  FinishUpdate(it, loss_value);
}

// --batch-size B > 1 (the reference's batch): B views, each rendered and back-propagated on its
// own with its gradient summed into grads_; the sum divided by B (the loss is the batch mean),
// one optimiser step over all rows, the statistics of the batch (BatchStats). Returns the mean
// loss.
double TrainingRun::BatchBackwardAndUpdate(int it, const float** ldr_out, std::size_t* pixels) {
  const int batch = opt_.batch_size;
  // Zeroed in place: the optimiser's groups point into grads_.
  for (std::vector<float>* field : GradientFields(&grads_)) std::fill(field->begin(), field->end(), 0.0f);
  view_grads_.ZerosLike(model_);
  batch_stats_.Begin(model_.size());
  double loss_sum = 0;
  for (int b = 0; b < batch; ++b) {
    const TrainView& view = train_views_[loop_.NextView(train_views_.size())];
    loss_sum += ViewLoss(view, it, ldr_out, pixels);
    RenderBackward(model_, camera_, view.time, render_, &state_, dL_dimage_.data(),
                   &view_grads_, {}, GeometryGradient());
    if (tone_mapper_) tone_mapper_->EndFrameBackward();
    AddGradients(view_grads_, &grads_);
    if (it < opt_.densify_until)
      batch_stats_.Add(state_.splat_grads.mean2d, state_.screen_radius,
                       camera_.intrinsics.width, camera_.intrinsics.height, coarse_);
    if (render_.track_max_weight) AccumulateMaxWeight(state_.splat_grads.max_weight, &stats_);
  }
  const float inverse = 1.0f / static_cast<float>(batch);
  ScaleGradients(inverse, &grads_);
  if (tone_mapper_)
    for (float& g : tone_mapper_->grads()) g *= inverse;
  if (background_)
    for (float& g : background_->grads()) g *= inverse;
  if (correction_) correction_->ScaleGrad(inverse);
  const GradientRowsDone step_rows = WithBandProbe(
      optimizer_->Begin(DensifiesAt(it), ResetsOpacityAt(it), model_.size(), ActiveRestColumns()));
  if (step_rows) {
    const std::size_t channels = static_cast<std::size_t>(model_.channels);
    const std::size_t stride = model_.rest_stride();
    ParallelForChunks(static_cast<std::int64_t>(model_.size()), 1024,
                      [&](std::int64_t b, std::int64_t e) {
                        step_rows(b, e,
                                  GradientRows{grads_.color_dc.data() + b * channels,
                                               grads_.color_rest.data() + b * stride});
                      });
  }
  EndBandProbe(it, /*rows_stored=*/!step_rows);
  if (it < opt_.densify_until) batch_stats_.AddTo(&stats_);
  const double loss_value = loss_sum / batch;
  FinishUpdate(it, loss_value);
  return loss_value;
}

// After the backward: the finite check, the steps the backward did not take, the held-out
// evaluations due, then densification and the opacity reset on their schedule.
void TrainingRun::FinishUpdate(int it, double loss_value) {
  // A non-finite gradient stops training: the state in memory is partly stepped and dropped,
  // the last checkpoint kept.
  if (const std::string bad = optimizer_->FirstNonFinite(); !bad.empty()) {
    Fail(
        "train: iteration {}: non-finite gradient in parameter group '{}'; stopped, the last "
        "good checkpoint is {}",
        it, bad, checkpoint_path_.string());
  }
  loop_.loss_curve.push_back(loss_value);
  // On a densifying iteration this steps only the tone mapper and the background, which
  // densification leaves alone, so it may come first (ModelOptimizer::Finish).
  optimizer_->Finish();
  if (correction_) correction_->Step();
  // The held-out views are scored before this iteration's densification and opacity reset, as
  // the reference's training_report is: right after them the new Gaussians have not settled
  // and every opacity is 0.01, so a reading there (every one on a multiple of the interval)
  // read several dB low on a sparse capture. A run the val split stops here ends on the model
  // it scored. (A run's last iteration still densifies where its schedule says so, which no
  // default schedule does, so that a run extended with --resume continues exactly.)
  EvaluateHeldOut(it);
  if (Stopped()) return;
  if (DensifiesAt(it)) {
    DensifyParams params = DensifyParamsAt(opt_, extent_, it);
    if (const std::optional<GrowthStop> g = GrowthStopped()) {
      const auto frozen = static_cast<std::size_t>(g->gaussians);
      params.max_gaussians = params.max_gaussians > 0 ? std::min(params.max_gaussians, frozen)
                                                      : frozen;
    }
    DensifyAndPrune(&model_, &grads_, &optimizer_->adam(), &stats_, params, &loop_.rng);
    OrderByTime();
    ReturnFreedMemory();  // its temporaries (core/util/free_memory.h)
  }
  if (ResetsOpacityAt(it)) ResetOpacity(&model_, &optimizer_->adam());
}

// The training-view PSNR of the final LDR image against the target, in one sequential sum (the
// curve of results.json is bit for bit the seed binary's).
double TrainingRun::TrainingPsnr(const float* ldr_out, std::size_t pixels) const {
  double squared = 0;
  for (std::size_t i = 0; i < pixels * 3; ++i) {
    const double d = std::clamp(ldr_out[i], 0.0f, 1.0f) - gt_[i];
    squared += d * d;
  }
  return -10.0 * std::log10(std::max(squared / (pixels * 3), 1e-20));
}

// The loss, the training-view PSNR (none under HDR-only supervision) and the Gaussian count on
// the progress line; the PSNR is also kept for results.json.
void TrainingRun::ShowProgress(double loss_value, std::optional<double> psnr) {
  std::string shown = fmt::format("loss {:.4f}", loss_value);
  if (psnr) {
    loop_.psnr_curve.push_back(*psnr);
    shown += fmt::format(" psnr {:.2f}", *psnr);
  }
  progress_->Advance(1, fmt::format("{} N {}", shown, model_.size()));
}

void TrainingRun::EvaluateHeldOut(int it) {
  EvaluateValViews(it);
  // A run that stops here is scored once more at its end (Finish), on the same model; with
  // --keep-best-val the end scores the best val evaluation's, so the last model is scored here.
  if (options_.test_every > 0 && it % options_.test_every == 0 && it < opt_.iterations &&
      (!Stopped() || opt_.keep_best_val)) {
    // Time to quality: the curve against training time, read before this evaluation (its
    // seconds are not training; read after it, each point carried its own evaluation's).
    const double train_seconds = TrainingSeconds();
    const auto eval_start = std::chrono::steady_clock::now();
    nlohmann::json m = EvaluateTestViews(/*with_flip=*/false);  // the curve stays cheap
    spdlog::info("train: iteration {}: test {}", it, m.dump());
    m["iteration"] = it;
    m["train_seconds"] = train_seconds;
    m["gaussians"] = model_.size();
    loop_.test_curve.push_back(std::move(m));
    eval_seconds_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - eval_start).count();
  }
}

void TrainingRun::CheckpointIfDue(int it) {
  if (options_.checkpoint_every > 0 && it % options_.checkpoint_every == 0) {
    loop_.train_seconds = TrainingSeconds();
    Save(checkpoint_path_);
  }
}

// Warns, once, when a learned tone curve has gone flat over the scene's inputs; returns the
// warning ("" when none is flat).
std::string TrainingRun::FlatToneCurveCheck(int it) {
  if (!tone_mapper_ || !tone_mapper_->pointwise() || model_.color_mode != ColorMode::kLogHdr)
    return "";
  const std::pair<double, double> range = ToneCurveInputRange(model_, train_views_);
  const std::vector<FlatToneCurve> flat =
      FindFlatToneCurves(tone_mapper_.get(), num_times_, range.first, range.second);
  if (flat.empty()) return "";
  std::string warning = FlatToneCurveWarning(flat, tone_mapper_->config().kind, range, it);
  if (!flat_curve_shown_) spdlog::warn("{}", warning);
  flat_curve_shown_ = true;
  return warning;
}

nlohmann::json TrainingRun::EvaluateTestViews(bool with_flip) {
  return EvaluateOn(test_views_, with_flip);
}

nlohmann::json TrainingRun::EvaluateOn(const std::vector<TrainView>& views, bool with_flip) {
  ViewRenderer renderer = EvalRenderer();
  return EvaluateViews(&renderer, views, with_flip);
}

// The model's renderer as the evaluations use it: without the training's colour stage.
ViewRenderer TrainingRun::EvalRenderer() {
  RenderOptions base = render_;
  base.color_stage = nullptr;
  return ViewRenderer(model_, tone_mapper_.get(), resolved_, base, options_.background,
                      background_ ? &background_->params() : nullptr,
                      head_current_ ? &head_ : nullptr);
}

// --stop-on-val: the val views scored every stop_window iterations, before that iteration's
// densification and opacity reset (FinishUpdate). The time is the method's, so it stays in the
// training seconds; the stop reads the mean LDR PSNR alone, so nothing else is computed.
void TrainingRun::EvaluateValViews(int it) {
  if (!opt_.stop_on_val || opt_.stop_window <= 0 || it % opt_.stop_window != 0) return;
  ViewRenderer renderer = EvalRenderer();
  const double psnr = MeanLdrPsnr(&renderer, val_views_);
  spdlog::info("train: iteration {}: val PSNR {:.3f} dB", it, psnr);
  loop_.val_curve.push_back({{"iteration", it},
                             {"psnr", FiniteOrNull(psnr)},
                             {"train_seconds", TrainingSeconds()},
                             {"gaussians", model_.size()}});
  if (const std::optional<GrowthStop> g = GrowthStopped(); g && g->iteration == it) {
    spdlog::info("train: iteration {}: the val views did not improve on their best; the model "
                 "grows no further than its {} Gaussians (--grow-on-val)",
                 it, g->gaussians);
  }
  // The model as scored (this iteration's densification has not run yet), kept to be taken
  // back if no later evaluation improves on it.
  if (opt_.keep_best_val && BestValIteration() == it) Save(options_.out / kBestValName);
}

std::optional<int> TrainingRun::BestValIteration() const {
  const std::vector<HeldOutPoint> points = ValPoints();
  const std::optional<std::size_t> best = BestHeldOutIndex(points, opt_.stop_tolerance);
  return best ? std::optional<int>(points[*best].iteration) : std::nullopt;
}

void TrainingRun::RestoreBestValModel() {
  // Only a run the val split stopped: one out of time or at its length is left as it stands, so
  // that --resume continues it exactly (a longer run's stop may still take back a best).
  if (!opt_.keep_best_val || !opt_.stop_on_val || !Stopped() || best_val_restored_) return;
  const std::optional<int> best = BestValIteration();
  if (!best || *best == loop_.iteration) return;
  const fs::path file = options_.out / kBestValName;
  Checkpoint c;
  try {
    c = LoadCheckpoint(file);
    if (c.trainer.value("iteration", -1) != *best)
      Fail("{}: holds iteration {}, not that of the best val evaluation ({})", file.string(),
           c.trainer.value("iteration", -1), *best);
  } catch (const Error& e) {
    // The end of a long run is not thrown away for a lost copy: the last model stays.
    spdlog::warn("train: the best val evaluation's model (iteration {}) cannot be taken back: "
                 "{}; the run keeps its last model (iteration {})",
                 *best, e.what(), loop_.iteration);
    return;
  }
  LoadTrainingState(&c, file);
  BindOptimizer(/*resumed=*/true);
  best_val_restored_ = true;
  spdlog::info("train: the model of the best val evaluation (iteration {}) taken back from {}; "
               "the run ends with it at iteration {}",
               *best, file.string(), loop_.iteration);
}

std::vector<HeldOutPoint> TrainingRun::ValPoints() const {
  std::vector<HeldOutPoint> curve;
  for (const nlohmann::json& e : loop_.val_curve) {
    const nlohmann::json& p = e.at("psnr");
    curve.push_back({e.at("iteration").get<int>(), p.is_number() ? p.get<double>() : std::nan(""),
                     e.value("gaussians", std::int64_t{0})});
  }
  return curve;
}

std::optional<HeldOutPlateau> TrainingRun::HeldOutStop() const {
  return FindHeldOutPlateau(ValPoints(), opt_.stop_tolerance);
}

std::vector<const std::vector<float>*> TrainingRun::ExtraFloats() const {
  std::vector<const std::vector<float>*> extra = {&stats_.grad_accum, &stats_.denom,
                                                  &stats_.max_radii};
  // Sections at fixed places: an empty one stands for a part the run does not have.
  static const std::vector<float> kNone;
  const bool probe = bands_ && bands_->probing();
  const bool prune = opt_.prune_contribution > 0;
  if (head_current_ || prune || probe) extra.push_back(head_current_ ? &head_.offset : &kNone);
  if (prune || probe) extra.push_back(prune ? &stats_.max_weight : &kNone);  // kMaxWeightSection
  if (probe) extra.push_back(&bands_->sums());                             // kColorBandSection
  return extra;
}

void TrainingRun::FitHdrHeadIfAsked() {
  if (!resolved_.hdr_head || head_current_) return;
  // The colour degrees of the last iteration, as the test evaluation renders with.
  SetColorDegrees(loop_.iteration);
  // The trained model is saved first: a head that fails leaves a run that resumes to fit it.
  loop_.train_seconds = TrainingSeconds();
  Save(checkpoint_path_);
  HdrHeadFit fit;
  fit.model = &model_;
  fit.views = &train_views_;
  fit.render = render_;
  fit.background = background_ ? &*background_ : nullptr;
  fit.tone_mapper = tone_mapper_.get();
  fit.terms = terms_;
  fit.iterations = options_.hdr.hdr_head_iterations > 0 ? options_.hdr.hdr_head_iterations
                                                        : std::max(1, opt_.iterations / 2);
  fit.seed = options_.seed;
  const auto start = std::chrono::steady_clock::now();
  {
    Progress progress("hdr head", fit.iterations, options_.progress);
    head_ = FitHdrHead(fit, &progress);
  }
  head_current_ = true;
  spdlog::info("train: HDR head fitted in {} steps ({:.1f} s), output factor {:.4g}",
               fit.iterations,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
               std::exp(head_.log_scale));
}

void TrainingRun::Save(const fs::path& file) {
  // The live model and optimiser are streamed into the file, not copied (checkpoint.h).
  nlohmann::json trainer = loop_.ToJson();
  if (background_) trainer[kLearnedBackgroundKey] = background_->params();
  if (correction_) trainer[kCameraCorrectionKey] = correction_->ToJson();
  if (head_current_) trainer[kHdrHeadScaleKey] = head_.log_scale;
  if (bands_) trainer[kColorBandsKey] = bands_->ToJson();
  if (head_current_ && !head_.background.empty())
    trainer[kHdrHeadBackgroundKey] = head_.background;
  if (best_val_restored_) trainer[kBestValRestoredKey] = true;
  std::string tone_mapper_state;
  if (tone_mapper_) {
    std::ostringstream tm_state;
    tone_mapper_->Save(tm_state);
    tone_mapper_state = tm_state.str();
  }
  SaveCheckpoint(file,
                 CheckpointParts{.model = &model_,
                                 .trainer = &trainer,
                                 .extra_floats = ExtraFloats(),
                                 .adam_state = CheckpointSection::Of(optimizer_->adam()),
                                 .tone_mapper_state = CheckpointSection::Of(tone_mapper_state)});
}

// After the last checkpoint nothing needs the optimiser, the gradients or the training frame's
// buffers (the test renderer has its own): released before the final test evaluation, so the
// end of a run is not its peak (about 2 KB per Gaussian; docs/history/paper-configuration.md).
void TrainingRun::ReleaseTrainingState() {
  optimizer_.reset();
  grads_ = GaussianGradients{};
  view_grads_ = GaussianGradients{};
  state_ = FrameState{};
  stats_ = DensifyStats{};
  batch_stats_ = BatchStats{};
  ReturnFreedMemory();
}

// The last checkpoint, the final test metrics and RUN/results.json.
TrainSummary TrainingRun::Finish() {
  if (progress_) progress_->Finish();
  loop_.train_seconds = TrainingSeconds();
  Save(checkpoint_path_);
  ReleaseTrainingState();
  TrainSummary summary;
  summary.stopped_flat = Stopped();
  if (const std::optional<HeldOutPlateau> v = opt_.stop_on_val ? HeldOutStop() : std::nullopt) {
    spdlog::info("train: --iterations auto --stop-on-val: the val views' PSNR stopped improving "
                 "(best {:.3f} dB at iteration {}, {} evaluations since); stopped at iteration "
                 "{} of {}",
                 v->best_psnr, v->best_iteration, kHeldOutPatience, loop_.iteration,
                 opt_.iterations);
  } else if (summary.stopped_flat) {
    spdlog::info("train: --iterations auto: the training loss stopped improving (less than {} "
                 "over {} iterations); stopped at iteration {} of {}",
                 opt_.stop_tolerance, opt_.stop_window, loop_.iteration, opt_.iterations);
  }
  summary.stopped_by_time = loop_.iteration < opt_.iterations && !summary.stopped_flat;
  summary.test_metrics = EvaluateTestViews(/*with_flip=*/true);
  summary.train_seconds = loop_.train_seconds;
  summary.iterations = loop_.iteration;
  summary.model_iteration = ModelIteration();
  summary.gaussians = model_.size();
  summary.loss_curve = loop_.loss_curve;
  nlohmann::json warnings = nlohmann::json::array();
  if (std::string flat = FlatToneCurveCheck(loop_.iteration); !flat.empty())
    warnings.push_back(std::move(flat));
  nlohmann::json results = {
      {"method", options_.hdr.method},
      {"test", summary.test_metrics},
      {"train_seconds", summary.train_seconds},
      {"iterations", summary.iterations},
      {"gaussians", summary.gaussians},
      // The process's peak resident memory up to the final scores, in MiB as the benchmark
      // harness records its children's (getrusage).
      {"peak_rss_mb", static_cast<double>(PeakResidentBytes()) / (1024.0 * 1024.0)},
      {"test_views", test_views_.size()},
      {"final_loss",
       loop_.loss_curve.empty() ? nlohmann::json(nullptr) : FiniteOrNull(loop_.loss_curve.back())},
      {"stopped_by_time", summary.stopped_by_time},
      {"curve", CurveBlocks(loop_.loss_curve, loop_.psnr_curve, 256)},
      {"test_curve", loop_.test_curve},
      // What the run found wrong with itself at its end (a flat tone curve); empty when nothing.
      {"warnings", std::move(warnings)}};
  // The learned gains, camera by camera (natural log, R G B): what the correction found.
  if (correction_) results["camera_log_gains"] = correction_->log_gains();
  if (bands_) results[kColorBandsKey] = bands_->ToJson();
  if (opt_.stop_window > 0) results["stopped"] = StopRecord();
  if (opt_.stop_on_val) results["val_curve"] = loop_.val_curve;
  if (opt_.grow_on_val) {
    const std::optional<GrowthStop> g = GrowthStopped();
    results["growth_stopped"] =
        g ? nlohmann::json{{"iteration", g->iteration}, {"gaussians", g->gaussians}}
          : nlohmann::json(nullptr);
  }
  if (options_.test_every > 0) {
    nlohmann::json last = summary.test_metrics;
    last["iteration"] = loop_.iteration;
    last["train_seconds"] = loop_.train_seconds;
    // The model scored: the best val evaluation's when the stop took it back.
    if (best_val_restored_) last["model_iteration"] = ModelIteration();
    results["test_curve"].push_back(std::move(last));
  }
  WriteJsonFile(options_.out / "results.json", results);
  // The kept model is in the checkpoint now: the copy goes (a run at its length keeps it, as a
  // longer resumed run may still stop and take it back).
  if (best_val_restored_) {
    std::error_code ec;
    fs::remove(options_.out / kBestValName, ec);
  }
  return summary;
}

// --iterations auto: why the loop ended, at which iteration, and the rule it was under.
nlohmann::json TrainingRun::StopRecord() const {
  const std::string rule =
      opt_.stop_on_val
          ? fmt::format("mean LDR PSNR of the {} val views, scored every {} iterations (before "
                        "that iteration's densification), not lowering their error by {} "
                        "(relative) on the best for {} evaluations in a row",
                        val_views_.size(), opt_.stop_window, opt_.stop_tolerance,
                        kHeldOutPatience)
          : fmt::format("mean training loss over windows of {} iterations after densification "
                        "(until {}) improving by less than {} (relative)",
                        opt_.stop_window, opt_.densify_until, opt_.stop_tolerance);
  nlohmann::json r = {{"rule", rule},
                      {"window", opt_.stop_window},
                      {"tolerance", opt_.stop_tolerance},
                      {"iteration", loop_.iteration},
                      {"max_iterations", opt_.iterations}};
  const std::optional<LossPlateau> p = opt_.stop_on_val ? std::nullopt : Plateau();
  if (const std::optional<HeldOutPlateau> v = opt_.stop_on_val ? HeldOutStop() : std::nullopt) {
    r["reason"] = "val_plateau";
    r["best_val_iteration"] = v->best_iteration;
    r["best_val_psnr"] = v->best_psnr;
    r["last_val_psnr"] = v->last_psnr;
  } else if (p) {
    r["reason"] = "loss_plateau";
    r["previous_window_loss"] = p->previous;
    r["last_window_loss"] = p->last;
    r["improvement"] = p->improvement;
  } else {
    r["reason"] = loop_.iteration < opt_.iterations ? "max_seconds" : "max_iterations";
  }
  // The model kept and scored in "test": the best val evaluation's (RestoreBestValModel).
  if (opt_.stop_on_val) r["model_iteration"] = ModelIteration();
  return r;
}

}  // namespace

TrainSummary Train(const TrainOptions& options) {
  if (std::string problem = options.Validate(); !problem.empty()) Fail("train: {}", problem);
  const ThreadLimit thread_limit(options.threads);
  TrainingRun run(options);
  run.SetUp();
  run.OpenRunFolder();
  run.ResumeOrInitialise();
  if (run.AlreadyFinished()) return run.FinishedSummary();
  run.ShowSceneNotes();
  run.PrepareRendering();
  while (run.StepsLeft() && !run.OutOfTime()) run.Step();
  run.RestoreBestValModel();
  run.FitHdrHeadIfAsked();
  return run.Finish();
}

}  // namespace hdr4d::method
