// TrainingRun's held-out views: the periodic test curve, the val evaluations and the stop they
// decide, and --keep-best-val's best model.
#include "method/train/training_run.h"

#include <cmath>
#include <cstdint>

#include "core/files/json_util.h"
#include "core/util/error.h"
#include "method/train/test_evaluation.h"
#include "method/train/tone_curve_watch.h"

namespace hdr4d::method::training_run {

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

}  // namespace hdr4d::method::training_run
