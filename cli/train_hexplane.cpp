#include "cli/train_hexplane.h"

#include <fmt/format.h>

#include "baselines/hexplane/hexplane_config.h"
#include "baselines/hexplane/hexplane_render.h"
#include "baselines/scene_baselines.h"
#include "cli/flags.h"
#include "core/util/error.h"

namespace hdr4d::cli {

namespace hp = baselines::hexplane;

std::vector<std::string> TrainMethodNames() {
  std::vector<std::string> names = baselines::MethodNames();
  for (const std::string& m : hp::HexPlaneMethods()) names.push_back(m);
  return names;
}

std::shared_ptr<hp::HexPlaneTrainOptions> AddHexPlaneTrainFlags(CLI::App* cmd) {
  auto o = std::make_shared<hp::HexPlaneTrainOptions>();
  cmd->add_option_function<int>("--rays", [o](int n) { o->batch_rays = n; },
                                "Grid methods: rays per iteration (the reference's 4096)")
      ->check(Integer(1, 1 << 24));
  cmd->add_option_function<std::vector<std::int64_t>>(
         "--grid-voxels",
         [o](const std::vector<std::int64_t>& v) {
           o->voxels_init = v[0];
           o->voxels_final = v[1];
         },
         "Grid methods: voxel count at the start and after the last upsampling (the "
         "reference's 262144 8000000: 64^3 to 200^3)")
      ->expected(2)
      ->check(Integer(8, std::int64_t{1} << 32));
  cmd->add_option_function<std::vector<int>>(
         "--time-grid",
         [o](const std::vector<int>& v) {
           o->time_grid_init = v[0];
           o->time_grid_final = v[1];
         },
         "Grid methods: time cells at the start and at the end (the reference's 16 24)")
      ->expected(2)
      ->check(Integer(2, 1 << 16));
  cmd->add_option_function<std::string>(
         "--grid-background", [o](const std::string& v) { o->background_model = v; },
         "Grid methods: what rays that miss the scene see: fixed (the reference: --background), "
         "learned (one learned colour) or environment (learned from the view direction); "
         "neither learned one depends on time")
      ->check(CLI::IsMember({"fixed", "learned", "environment"}));
  return o;
}

bool TrainHexPlaneIfAsked(CLI::App* cmd, std::string method, hp::HexPlaneTrainOptions o) {
  // --resume of a grid run without --method: the run's own method.
  if (cmd->get_option("--resume")->count() > 0 && cmd->get_option("--method")->count() == 0 &&
      cmd->get_option("--out")->count() > 0) {
    if (const auto run_method = hp::HexPlaneMethodOfRun(cmd->get_option("--out")->as<std::string>()))
      method = *run_method;
  }
  const auto given = [cmd](const char* flag) { return cmd->get_option(flag)->count() > 0; };
  if (!hp::IsHexPlaneMethod(method)) {
    for (const char* flag : {"--rays", "--grid-voxels", "--time-grid", "--grid-background"})
      if (given(flag))
        Fail("train: {} applies to the grid methods only (--method {})", flag, method);
    return false;
  }
  for (const char* flag : {"--config", "--tone-mapper", "--batch-size", "--max-gaussians",
                           "--hdr-head", "--learn-background", "--camera-correction",
                           "--camera-correction-weight", "--camera-correction-lr"}) {
    if (given(flag)) Fail("train: {} does not apply to --method {}", flag, method);
  }
  o.method = method;
  // Only what was given: the grid family keeps its own defaults (HexPlaneTrainOptions) for the
  // rest, and an option table row without a shown default has no text to convert.
  if (given("--data")) o.data = cmd->get_option("--data")->as<std::string>();
  if (given("--out")) o.out = cmd->get_option("--out")->as<std::string>();
  if (given("--threads")) o.threads = cmd->get_option("--threads")->as<int>();
  if (given("--resolution")) o.resolution = cmd->get_option("--resolution")->as<int>();
  if (given("--max-seconds")) o.max_seconds = cmd->get_option("--max-seconds")->as<double>();
  if (given("--background")) o.background = cmd->get_option("--background")->as<float>();
  if (given("--supervision")) o.supervision = cmd->get_option("--supervision")->as<std::string>();
  if (given("--exposure-unit"))
    o.exposure_unit =
        ParseExposureUnit(cmd->get_option("--exposure-unit")->as<std::string>(), "train");
  if (given("--iterations")) o.iterations = cmd->get_option("--iterations")->as<int>();
  if (given("--seed")) o.seed = cmd->get_option("--seed")->as<std::int64_t>();
  if (given("--hdr-weight")) o.hdr_weight = cmd->get_option("--hdr-weight")->as<float>();
  if (given("--checkpoint-every"))
    o.checkpoint_every = cmd->get_option("--checkpoint-every")->as<int>();
  o.resume = given("--resume");
  if (o.data.empty() && !o.resume) Fail("train: --data is required");
  if (o.out.empty()) Fail("train: --out is required");
  const hp::HexPlaneTrainSummary s = hp::TrainHexPlane(o);
  fmt::print("train: {} iterations in {:.1f} s; test {}\n", s.iterations, s.train_seconds,
             s.test_metrics.dump());
  return true;
}

}  // namespace hdr4d::cli
