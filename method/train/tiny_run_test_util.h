// Test helper: a tiny known scene and training options whose schedules (densification, opacity
// resets, the colour bands) all happen within a few dozen iterations, shared by the trainer's
// tests so that each states only what it changes.
#pragma once

#include <filesystem>

#include "core/dataset/demo_scene.h"
#include "core/files/json_util.h"
#include "core/radiometry/exposure_stack.h"
#include "method/train/trainer.h"

namespace hdr4d::method::train_testing {

// The built-in demo scene at SIZE x SIZE, 3 times and 3 cameras (the last held out), with LDR
// brackets synthesised from its HDR.
inline void MakeTinyHdrScene(const std::filesystem::path& root, int size) {
  DemoSceneOptions s;
  s.width = s.height = size;
  s.num_timestamps = 3;
  s.num_cameras = 3;
  s.samples_per_axis = 1;
  MakeDemoScene(s, root);
  DatasetSynthesisOptions ldr;
  ldr.noise.seed = 1;
  SynthesizeDatasetLdr(root, ldr);
}

// Makes a scene static: every frame of its train and test splits at time 0.
inline void MakeStatic(const std::filesystem::path& root) {
  for (const char* split : {"transforms_train.json", "transforms_test.json"}) {
    nlohmann::json j = ReadJsonFile(root / split);
    for (auto& frame : j["frames"]) frame["time"] = 0.0;
    WriteJsonFile(root / split, j);
  }
}

// 400 random points; densification, opacity reset and the SH schedule within 60 iterations
// (a low gradient threshold: densify often on a tiny scene).
inline TrainOptions TinyRunOptions(const std::filesystem::path& scene,
                                   const std::filesystem::path& run, int iterations, int seed) {
  TrainOptions o;
  o.data = scene;
  o.out = run;
  o.seed = seed;
  o.progress = false;
  o.init.num_random_points = 400;
  OptimizationOptions& opt = o.optimization;
  opt.iterations = iterations;
  opt.densify_from = 10;
  opt.densification_interval = 10;
  opt.densify_until = 50;
  opt.opacity_reset_interval = 30;
  opt.sh_increase_interval = 10;
  opt.position_lr_max_steps = 60;
  opt.densify_grad_threshold = 1e-5;
  return o;
}

}  // namespace hdr4d::method::train_testing
