// `hdr4d train`: 4D Gaussian Splatting from a dataset (ARCHITECTURE §4): initialisation, the training
// loop (render, L1 + D-SSIM, backward, Adam with the reference's schedules, densification),
// periodic test evaluation, checkpoints that resume exactly, and RUN/results.json.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/dataset/dataset.h"
#include "method/optim/lr_schedule.h"
#include "method/train/hdr_training_options.h"
#include "method/train/initialise.h"

namespace hdr4d::method {

struct TrainOptions {
  std::filesystem::path data;  // scene folder
  // How the scene's `exposures` are read ("seconds" or "stops", core/dataset/dataset.h);
  // recorded, so render and --resume read the scene the same way.
  std::string exposure_unit = "seconds";
  std::filesystem::path out;   // run folder
  OptimizationOptions optimization;
  InitOptions init;  // seed, random point count, ...
  std::uint64_t seed = 0;
  int threads = 0;           // 0 = all cores
  // Images reduced this many times on load, train and test views alike (LoadViews); render and
  // eval of the run read it from RUN/config.json.
  int resolution = 1;
  int test_every = 0;        // evaluate the test split every N iterations (0 = only at the end)
  int checkpoint_every = 0;  // save RUN/checkpoint.bin every N iterations (0 = only at the end)
  // Wall-clock budget of the training loop in seconds (0 = none): training stops after the first
  // iteration that reaches it (the schedules still run over optimization.iterations).
  double max_seconds = 0;
  bool resume = false;       // continue from RUN/checkpoint.bin
  // --reference: the paper-faithful configuration (the defaults before issue 55, bit for bit):
  // every option that does less than the paper's training (visible-set Adam, --iterations auto)
  // off; Validate refuses one of them given with it.
  bool reference = false;
  // A new run in a folder holding an earlier one deletes its files first (run_folder.h); without
  // it such a folder is refused.
  bool overwrite = false;
  bool progress = true;
  float background = 0.0f;  // grey level behind the scene (the reference trains on black)
  // Learn one background colour with the scene (learned_background.h; not in the paper, whose
  // background is fixed at `background`): a log radiance through the tone mapper for log-HDR
  // colours, else an LDR colour starting at `background`. Saved in the checkpoint; render and
  // eval use it. Unset: on for a new run (docs/history/accuracy.md, the learned-background
  // sections: never worse beyond seed noise, +0.9 to +2.2 dB held-out where a sky is seen from
  // few cameras); a resumed run keeps what it started with (runs from before the option: off).
  std::optional<bool> learn_background;
  // Learn a log gain per channel for each training camera, added to the tone curve's input
  // (method/tonemap/camera_correction.h; not in the paper): a rig whose cameras differ in gain or
  // white balance. Needs a tone mapper. Regulariser weight * |d|^2 and Adam's rate on d.
  bool camera_correction = false;
  double camera_correction_weight = 0.01;
  double camera_correction_lr = 0.002;
  HdrTrainingOptions hdr;   // colour mode, tone mapper, supervision branches (plain 4DGS default)
  // When set: the options trained instead of `hdr` when every training frame has the same
  // exposure and no frame has HDR ground truth (nothing to recover an HDR from), with a note
  // saying so. `hdr4d train` sets plain 4DGS here unless the method, tone mapper or
  // supervision was asked for.
  std::optional<HdrTrainingOptions> when_nothing_hdr;
  // Set by `hdr4d train` when no run length was asked for: a scene with a val split then trains
  // as --iterations auto --stop-on-val, and records it so (issue 55; a resumed run keeps what
  // it recorded). Not an option of its own: --iterations N trains N.
  bool stop_on_val_where_split = false;
  // "" or the first problem: a member outside its option's range (train_options_table.h, in
  // the words of the flag's help), then the optimisation's and the colour model's own checks.
  std::string Validate() const;
  // RUN/config.json's record: every row of the option table at its key.
  nlohmann::json ToJson() const;
  // The options RUN/config.json recorded (ToJson's keys, schedules as the run resolved them;
  // `out` is the folder of `source`, threads keep the default): what `hdr4d train --resume`
  // trains unless a flag says otherwise.
  // Throws hdr4d::Error naming `source` and the missing or bad key.
  static TrainOptions FromJson(const nlohmann::json& json, const std::string& source);
};

struct TrainSummary {
  nlohmann::json test_metrics;  // keys of `hdr4d eval` (means over the test views), LDR and HDR
  double train_seconds = 0;
  int iterations = 0;
  std::size_t gaussians = 0;
  std::vector<double> loss_curve;  // per iteration
  bool stopped_by_time = false;    // max_seconds ended the loop before optimization.iterations
  bool stopped_flat = false;       // --iterations auto ended it (the loss stopped improving)
  // The iteration of the model kept and scored: `iterations`, or the best val evaluation's
  // when --stop-on-val took that model back at the stop.
  int model_iteration = 0;
};

// Runs (or resumes) training; writes RUN/config.json, RUN/checkpoint.bin, RUN/results.json.
// results.json also holds the training curves ("curve": loss and training-view PSNR as means
// over at most 256 equal blocks of iterations) and, with test_every, the test metrics at each
// evaluation ("test_curve"). train_seconds is the loop's wall time without those evaluations.
TrainSummary Train(const TrainOptions& options);

// The radiance-bank size of a scene: the number of distinct normalised timestamps over all its
// frames (the reference's len(set(times))).
int DistinctTimes(const Dataset& dataset);


}  // namespace hdr4d::method
