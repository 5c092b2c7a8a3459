// hdr4d make-demo-scene: the built-in dynamic HDR scene as a dataset (HDR ground truth + JSON).
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/dataset/demo_scene.h"
#include "core/util/error.h"

namespace hdr4d::cli {

void AddDemoSceneCommand(CLI::App& app) {
  auto options = std::make_shared<DemoSceneOptions>();
  auto out = std::make_shared<std::string>();
  auto rig = std::make_shared<std::string>("multiview");
  CLI::App* cmd = app.add_subcommand(
      "make-demo-scene",
      "Render the built-in dynamic HDR scene (a rolling ball, a glowing bulb whose lamp casts a moving shadow, a dimming sun; "
      "radiance over 1e4:1) to linear EXR ground truth and write its dataset JSON. Then run "
      "`hdr4d synth-ldr --data DIR` to create the multi-exposure LDR images.");
  cmd->add_option("--out,-o", *out, "Output folder (new, or empty)")
      ->required()
      ->check(Text("an output folder"));
  cmd->add_option("--size", options->width, "Image width and height in pixels")
      ->check(Integer(8, 4096))
      ->capture_default_str();
  cmd->add_option("--timestamps", options->num_timestamps, "Number of timestamps")
      ->check(Integer(1, 100000))
      ->capture_default_str();
  cmd->add_option("--cameras", options->num_cameras,
                  "Multi-view: number of fixed cameras (the last is held out for test)")
      ->check(Integer(1, 10000))
      ->capture_default_str();
  cmd->add_option("--rig", *rig,
                  "multiview (every exposure at every camera and time) or monocular (one moving "
                  "camera, exposures cycling)")
      ->check(OneOf({"multiview", "monocular"}))
      ->capture_default_str();
  cmd->add_option("--exposures", options->exposures, "Exposure times in seconds")
      ->delimiter(',')
      ->check(PositiveReal())
      ->capture_default_str();
  cmd->add_option("--spp", options->samples_per_axis, "Supersampling: N x N rays per pixel")
      ->check(Integer(1, 16))
      ->capture_default_str();
  cmd->callback([options, out, rig] {
    options->height = options->width;
    options->rig = *rig == "monocular" ? DemoRig::kMonocular : DemoRig::kMultiView;
    const Dataset dataset = MakeDemoScene(*options, *out);
    fmt::print(
        "make-demo-scene: {} train and {} test frames in {} (HDR in hdr/, LDR to come in "
        "images/)\n",
        dataset.train.size(), dataset.test.size(), *out);
  });
}

}  // namespace hdr4d::cli
