// The one training run behind `Train` (trainer.h), shared by the files that implement its
// stages: training_run_setup.cpp (the scene, the schedules, the configuration),
// training_run_start.cpp (the run folder, resume or initialise, rendering), training_run_step.cpp
// (one step: forward, loss, backward, update, densification), training_run_held_out.cpp (test and
// val evaluations, the val stop) and training_run_finish.cpp (the checkpoint, results.json).
// Internal to method/train.
#pragma once

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/dataset/dataset_checksum.h"
#include "core/dataset/scene_profile.h"
#include "core/files/folder_lock.h"
#include "core/files/output_guard.h"
#include "core/geometry/ply.h"
#include "core/util/progress.h"
#include "method/optim/densify.h"
#include "method/optim/model_optimizer.h"
#include "method/render/hdr_color_stage.h"
#include "method/render/learned_background.h"
#include "method/render/view_renderer.h"
#include "method/tonemap/camera_correction.h"
#include "method/tonemap/radiance_bank.h"
#include "method/train/checkpoint.h"
#include "method/train/color_bands.h"
#include "method/train/hdr_head_fit.h"
#include "method/train/hdr_loss.h"
#include "method/train/loop_state.h"
#include "method/train/loss_plateau.h"
#include "method/train/run_folder.h"
#include "method/train/train_views.h"
#include "method/train/trainer.h"

namespace hdr4d::method::training_run {
namespace fs = std::filesystem;

// --prune-contribution's blending-weight statistics in a checkpoint: the extra float section after
// the HDR head's (an empty head section when the run has none).
inline constexpr std::size_t kMaxWeightSection = kHdrHeadSection + 1;
// --color-bands-by-need: the sums of a colour-band probe under way (empty when none runs).
inline constexpr std::size_t kColorBandSection = kMaxWeightSection + 1;
inline constexpr const char* kColorBandsKey = "color_bands";

inline constexpr const char* kCheckpointName = "checkpoint.bin";
// --keep-best-val: the model of the best val evaluation so far, written when one improves on the
// best and taken back at the stop (RestoreBestValModel); removed once results.json is written.
inline constexpr const char* kBestValName = "best_val.bin";
// In the trainer state: the live model is the best val evaluation's, taken back at the end.
inline constexpr const char* kBestValRestoredKey = "best_val_restored";

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
  std::string WhatIsKept() const;  // for the errors that stop a run: its last checkpoint, or none
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
  std::optional<RunFolderWriter> writer_;  // this run's files are ours to write (output_guard.h)
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

}  // namespace hdr4d::method::training_run
