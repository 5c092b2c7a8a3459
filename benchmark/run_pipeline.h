// One run of a suite, start to finish, as child processes of the hdr4d binary:
//   hdr4d train --data SCENE --out DIR/train --threads T <train args>   (--resume after a kill)
//   hdr4d render --run DIR/train --split test --out DIR/renders --timing DIR/render_timing.json
//   hdr4d tone-curves --run DIR/train --out DIR/tone_curves            (pointwise tone mappers)
// then the renders are scored in-process with core's evaluation (benchmark/scoring.h) and
// everything is gathered into one RunRecord. A step that fails makes a record with status
// "failed" and the step's error line; cancellation (the harness stopping) makes none, and the
// run's folder is kept so the next attempt resumes its training.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "benchmark/run_plan.h"
#include "benchmark/run_record.h"

namespace hdr4d::bench {

struct PipelineOptions {
  std::filesystem::path runs_dir;  // each run works in runs_dir/<run id>
  std::filesystem::path hdr4d;     // the binary
  int threads = 1;                 // per child
  const std::atomic<bool>* cancel = nullptr;
  std::string source = "harness";
  bool keep_checkpoint = false;  // checkpoints are large; renders and curves are kept
};

// Times at which tone curves are sampled for the report.
inline constexpr const char* kToneCurveTimes = "0,0.25,0.5,0.75,1";

// nullopt only when cancelled. `on_stage` (optional) hears "train", "render", "score".
std::optional<RunRecord> ExecuteRun(const RunSpec& run,
                                    const PipelineOptions& options,
                                    const std::function<void(const std::string&)>& on_stage = {});

// Reads DIR/tone_curves/tone_curves.csv into series "tone:<time>:<r|g|b>".
void ReadToneCurveSeries(const std::filesystem::path& csv, RunRecord* record);

}  // namespace hdr4d::bench
