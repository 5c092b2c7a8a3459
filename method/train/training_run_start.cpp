// TrainingRun's start: the run folder, a checkpoint resumed or a model initialised, the
// optimiser bound to it, and what rendering the steps needs.
#include "method/train/resume_check.h"
#include "method/train/training_run.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"
#include "core/util/free_memory.h"
#include "method/gaussian/constants.h"
#include "method/optim/lr_schedule.h"

namespace hdr4d::method::training_run {

// One writer per run folder; a folder this run made and left with nothing in it on failure is
// removed again, so a failed start leaves nothing a later command trips over.
void TrainingRun::OpenRunFolder() {
  CheckOutputFolder(options_.out);  // before the folder or anything in it is made
  std::error_code ec;
  const bool made_folder = !fs::exists(options_.out, ec);
  fs::create_directories(options_.out, ec);
  if (ec) Fail("{}: cannot create the run folder: {}", options_.out.string(), ec.message());
  // The clean-up is armed once the lock is ours: a writer that holds it owns what is there.
  writer_.emplace(options_.out);  // first: taking the lock writes the lock file's holder line
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
    nlohmann::json recorded = nlohmann::json::object();  // the state below takes parts of c
    if (const auto it = c.trainer.find(kRunConfigKey); it != c.trainer.end())
      recorded[kRunConfigKey] = *it;
    loop_.FromJson(c.trainer, checkpoint_path_, train_views_.size());
    LoadTrainingState(&c, checkpoint_path_);
    // After the checks of each part, which say more; before the optimiser binds the state.
    RequireCheckpointOfThisConfig(recorded, config_, options_.out / "config.json",
                                  checkpoint_path_);
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
  if (random && cloud) {  // the user gave a cloud: say why it is not used (stop 94 sweep)
    spdlog::warn("train: {} has {} point{}, fewer than the {} a cloud needs to start from: the "
                 "model starts from {} random points instead (--random-points)",
                 dataset_->point_cloud_path->string(), cloud->size(),
                 cloud->size() == 1 ? "" : "s", kMinInitialPoints, init.num_random_points);
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

}  // namespace hdr4d::method::training_run
