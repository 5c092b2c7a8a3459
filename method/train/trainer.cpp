#include "method/train/trainer.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/train/train_options_table.h"
#include "method/train/training_run.h"

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

TrainSummary Train(const TrainOptions& options) {
  if (std::string problem = options.Validate(); !problem.empty()) Fail("train: {}", problem);
  const ThreadLimit thread_limit(options.threads);
  training_run::TrainingRun run(options);
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
