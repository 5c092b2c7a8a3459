// hdr4d train: 4D Gaussian Splatting on a dataset.
#include <fmt/format.h>

#include "cli/commands.h"
#include "method/trainer.h"

namespace hdr4d::cli {

void AddTrainCommand(CLI::App& app) {
  auto options = std::make_shared<method::TrainOptions>();
  auto data = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "train",
      "Train 4D Gaussian Splatting on a scene (a static scene trains without the time axis). "
      "Writes RUN/config.json, RUN/checkpoint.bin and RUN/results.json (test metrics with the "
      "keys of `hdr4d eval`, training seconds, iterations, Gaussian count).");
  cmd->add_option("--data", *data, "Scene folder")->required();
  cmd->add_option("--out", *out, "Run folder")->required();
  cmd->add_option("--iterations", options->optimization.iterations, "Training iterations")
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "Random seed (same seed and threads: identical runs)")
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--random-points", options->init.num_random_points,
                  "Initial random points when the scene has no point3d.ply")
      ->capture_default_str();
  cmd->add_option("--densify-until", options->optimization.densify_until,
                  "Last densification iteration")
      ->capture_default_str();
  cmd->add_option("--densify-grad-threshold", options->optimization.densify_grad_threshold,
                  "Clone/split when the mean NDC screen gradient reaches this")
      ->capture_default_str();
  cmd->add_option("--position-lr-steps", options->optimization.position_lr_max_steps,
                  "Iterations over which the position learning rate decays")
      ->capture_default_str();
  cmd->add_option("--test-every", options->test_every,
                  "Evaluate the test split every N iterations (0: at the end)")
      ->capture_default_str();
  cmd->add_option("--checkpoint-every", options->checkpoint_every,
                  "Save RUN/checkpoint.bin every N iterations")
      ->capture_default_str();
  cmd->add_option("--background", options->background, "Background grey level in [0,1]")
      ->capture_default_str();
  cmd->add_flag("--resume", options->resume,
                "Continue from RUN/checkpoint.bin (exactly as if never stopped)");
  cmd->callback([options, data, out] {
    options->data = *data;
    options->out = *out;
    const method::TrainSummary s = method::Train(*options);
    fmt::print("train: {} iterations in {:.1f} s, {} Gaussians; test {}\n", s.iterations,
               s.train_seconds, s.gaussians, s.test_metrics.dump());
  });
}

}  // namespace hdr4d::cli
