// hdr4d make-gaussian-scene: a known 4D Gaussian scene rendered to a dataset (the engine's
// ground truth: training from random points must recover it).
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/flags.h"
#include "method/run/gaussian_scene.h"

namespace hdr4d::cli {

void AddGaussianSceneCommand(CLI::App& app) {
  auto options = std::make_shared<method::GaussianSceneOptions>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "make-gaussian-scene",
      "Render a known scene of moving, turning 4D Gaussians from a ring of cameras over time to "
      "a dataset (every 4th camera held out for test): the ground truth `hdr4d train` must "
      "recover.");
  cmd->add_option("--out,-o", *out, "Output folder (new, or empty)")
      ->required()
      ->check(Text("an output folder"));
  cmd->add_option("--size", options->size, "Image width and height")
      ->check(Integer(16, 2048))
      ->capture_default_str();
  cmd->add_option("--gaussians", options->num_gaussians, "Number of Gaussians")
      ->check(Integer(1, 10'000'000))
      ->capture_default_str();
  cmd->add_option("--cameras", options->num_cameras, "Cameras on the ring")
      ->check(Integer(4, 10000))
      ->capture_default_str();
  cmd->add_option("--timestamps", options->num_timestamps, "Timestamps in [0,1]")
      ->check(Integer(2, 100000))
      ->capture_default_str();
  cmd->add_option("--sh-degree", options->sh_degree,
                  "Colours that change with the viewing direction up to this SH degree (0: "
                  "every view agrees on a Gaussian's colour)")
      ->check(Integer(0, 3))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "Random seed of the scene")
      ->check(Seed())
      ->capture_default_str();
  cmd->callback([options, out] {
    const Dataset d = method::MakeGaussianScene(*options, *out);
    fmt::print("make-gaussian-scene: {} train and {} test frames in {}\n", d.train.size(),
               d.test.size(), *out);
  });
}

}  // namespace hdr4d::cli
