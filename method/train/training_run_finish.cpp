// TrainingRun's end: the checkpoint, the HDR head's fit, the test metrics and results.json.
#include "method/train/training_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/files/json_util.h"
#include "core/util/free_memory.h"

namespace hdr4d::method::training_run {

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
  trainer[kRunConfigKey] = config_;  // what a reader checks config.json against (resume_check.h)
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

}  // namespace hdr4d::method::training_run
