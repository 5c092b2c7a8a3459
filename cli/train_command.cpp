// hdr4d train: HDR-4DGS (or one of the paper's baselines) on a dataset.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "baselines/scene_baselines.h"
#include "cli/commands.h"
#include "cli/flags.h"
#include "cli/train_hexplane.h"
#include "core/util/error.h"
#include "method/tonemap/tone_mapper_registry.h"
#include "method/train/resume_check.h"
#include "method/train/train_config.h"
#include "method/train/trainer.h"

namespace hdr4d::cli {
namespace {

// `hdr4d train --list-configs`: every preset with its values, then the keys of a file.
void ListTrainConfigs() {
  for (const method::TrainPreset& p : method::TrainPresets())
    fmt::print("{:<20} {}\n{:<20} {}\n", p.name, p.what, "", p.values.dump());
  std::vector<std::string> keys;
  for (const method::TrainConfigKey& k : method::TrainConfigKeys())
    keys.push_back(k.flag.empty() ? k.name : fmt::format("{} ({})", k.name, k.flag));
  fmt::print("\nA --config FILE is a JSON object with any of these keys (flag that wins over it):\n"
             "  {}\n",
             fmt::join(keys, "\n  "));
}

// `hdr4d train --resume`: the options the run recorded (saved), with every option given on the
// command line (in `flags`, as parsed) put over them. What differs from the run's configuration
// is then refused by the trainer, before the scene is read, except what may change on a resume
// (the run length, threads, test and checkpoint cadence, time budget). Threads are never taken
// from the record: a resumed run uses this machine's cores unless told.
method::TrainOptions ResumedOptions(const method::TrainOptions& saved,
                                    const method::TrainOptions& flags,
                                    const std::function<bool(const std::string&)>& given) {
  method::TrainOptions run = saved;
  // The field an option sets, taken from `flags` when the option was given.
  const auto take = [&](const char* flag, auto field) {
    if (given(flag)) field(run) = field(flags);
  };
  take("--data", [](auto& o) -> auto& { return o.data; });
  take("--iterations", [](auto& o) -> auto& { return o.optimization.iterations; });
  take("--seed", [](auto& o) -> auto& { return o.seed; });
  take("--resolution", [](auto& o) -> auto& { return o.resolution; });
  take("--batch-size", [](auto& o) -> auto& { return o.optimization.batch_size; });
  take("--max-gaussians", [](auto& o) -> auto& { return o.optimization.max_gaussians; });
  take("--random-points", [](auto& o) -> auto& { return o.init.num_random_points; });
  take("--densify-from", [](auto& o) -> auto& { return o.optimization.densify_from; });
  take("--densify-until", [](auto& o) -> auto& { return o.optimization.densify_until; });
  take("--densification-interval",
       [](auto& o) -> auto& { return o.optimization.densification_interval; });
  take("--densify-grad-threshold",
       [](auto& o) -> auto& { return o.optimization.densify_grad_threshold; });
  take("--position-lr-steps",
       [](auto& o) -> auto& { return o.optimization.position_lr_max_steps; });
  take("--opacity-reset-interval",
       [](auto& o) -> auto& { return o.optimization.opacity_reset_interval; });
  take("--sh-increase-interval",
       [](auto& o) -> auto& { return o.optimization.sh_increase_interval; });
  take("--color-lr", [](auto& o) -> auto& { return o.optimization.f_dc_lr; });
  take("--color-lr", [](auto& o) -> auto& { return o.optimization.f_dc_lr_log_hdr; });
  take("--test-every", [](auto& o) -> auto& { return o.test_every; });
  take("--max-seconds", [](auto& o) -> auto& { return o.max_seconds; });
  take("--checkpoint-every", [](auto& o) -> auto& { return o.checkpoint_every; });
  take("--background", [](auto& o) -> auto& { return o.background; });
  take("--learn-background", [](auto& o) -> auto& { return o.learn_background; });
  run.out = flags.out;
  run.resume = true;
  run.threads = flags.threads;
  run.progress = flags.progress;
  run.hdr = flags.hdr;  // the run's own, with the HDR flags given (AddTrainCommand)
  return run;
}

}  // namespace

void AddTrainCommand(CLI::App& app) {
  auto options = std::make_shared<method::TrainOptions>();
  auto data = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  struct HdrFlags {
    std::string method = "hdr4dgs";
    std::string tone_mapper, supervision = "auto", context_learner;
    bool no_pixel_branch = false, no_gaussian_branch = false, direct_curves = false,
         monotone_curves = false;
    int context_window = 20, context_size = 2;
    float hdr_weight = 0.6f;
    float pixel_log_epsilon = 0.0f;
    std::string hdr_target;
    bool no_hdr_geometry = false;
    bool hdr_head = false;
    int hdr_head_iterations = 0;
  };
  auto flags = std::make_shared<HdrFlags>();
  auto config = std::make_shared<std::string>();
  auto list_configs = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "train",
      "Train HDR-4DGS (log-HDR 4D Gaussians + the Dynamic Tone Mapper) or one of the paper's "
      "baselines on a scene (a static scene trains without the time axis). Writes "
      "RUN/config.json, RUN/checkpoint.bin and RUN/results.json (test metrics with the keys of "
      "`hdr4d eval`, LDR and HDR, training seconds, iterations, Gaussian count).");
  CLI::Option* data_flag =
      cmd->add_option("--data", *data, "Scene folder (with --resume: the run's own by default)")
          ->check(Text("a scene folder"));
  CLI::Option* out_flag =
      cmd->add_option("--out", *out, "Run folder")->check(Text("a run folder"));
  cmd->add_option("--iterations", options->optimization.iterations,
                  "Training iterations. The schedules (densification window, position "
                  "learning-rate decay, opacity resets) follow it: "
                  "the reference's values are those of 20000 iterations; a flag given below "
                  "wins over the scaling")
      ->check(Integer(1))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "Random seed (same seed and threads: identical runs)")
      ->check(Seed())
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Threads (0 = all cores)")
      ->check(Integer(0, 4096))
      ->capture_default_str();
  cmd->add_option("--resolution", options->resolution,
                  "Train at 1/R of the images' size: every image (LDR and HDR, train and test) "
                  "is box-averaged over R x R pixels on load and the intrinsics divided by R; "
                  "R must divide the images' width and height (the reference: 2 for "
                  "HDR-4D-Syn, 4 for HDR-4D-Real). `hdr4d render` uses the run's R")
      ->check(Integer(1, 1 << 16))
      ->capture_default_str();
  cmd->add_option("--batch-size", options->optimization.batch_size,
                  "Views per iteration (the reference's batch_size): the loss is their mean, "
                  "one optimiser step per batch, densification statistics as the reference "
                  "accumulates them; --iterations counts batches")
      ->check(Integer(1, 4096))
      ->capture_default_str();
  cmd->add_option("--max-gaussians", options->optimization.max_gaussians,
                  "Gaussian budget (the reference's densify_until_num_points): densification "
                  "never takes the count past N, keeping the clone/split candidates with the "
                  "largest gradients; 0 = no budget (default: 2 x the pixels of one training "
                  "view, of every view for a static scene, at least 32768; "
                  "docs/history/gaussian-budget.md)")
      ->check(Integer(0, std::int64_t{1} << 40));
  cmd->add_option("--config", *config,
                  "Training configuration: a JSON file of option names and values "
                  "(iterations, batch_size, resolution, max_gaussians, densify_until, ...) or a "
                  "preset of the reference's per-scene settings (syn/lego, real/bed, dnerf/trex, "
                  "...; --list-configs). A flag given here wins over it; RUN/config.json keeps "
                  "the resolved values")
      ->check(Text("a configuration file or preset name"));
  cmd->add_flag("--list-configs", *list_configs,
                "List the presets of --config with their values and the keys a file may hold, "
                "then exit");
  cmd->add_option("--random-points", options->init.num_random_points,
                  "Initial random points when the scene has no point3d.ply")
      ->check(Integer(4, 100'000'000))
      ->capture_default_str();
  method::OptimizationOptions& o = options->optimization;
  cmd->add_option("--densify-from", o.densify_from,
                  "First densification iteration (default: 2.5% of --iterations, the "
                  "reference's 500 of 20000)")
      ->check(Integer(0));
  cmd->add_option("--densify-until", o.densify_until,
                  "Last densification iteration (default: 75% of --iterations, 15000 of 20000)")
      ->check(Integer(0));
  cmd->add_option("--densification-interval", o.densification_interval,
                  "Iterations between densifications (the reference's, whatever the run length)")
      ->check(Integer(1))
      ->capture_default_str();
  cmd->add_option("--densify-grad-threshold", o.densify_grad_threshold,
                  "Clone/split when the mean NDC screen gradient reaches this (default: the "
                  "reference's 2e-4 at 400 px, times 400 / the image size: 8e-4 at 100 px)")
      ->check(PositiveReal());
  cmd->add_option("--position-lr-steps", o.position_lr_max_steps,
                  "Iterations over which the position learning rate decays (default: 75% of "
                  "--iterations, 15000 of 20000)")
      ->check(Integer(1));
  cmd->add_option("--opacity-reset-interval", o.opacity_reset_interval,
                  "Iterations between opacity resets while densifying (default: the reference's "
                  "3000 whatever --iterations: more frequent resets leave no time to recover)")
      ->check(Integer(1));
  cmd->add_option("--sh-increase-interval", o.sh_increase_interval,
                  "Iterations per colour degree step, spatial 0->3 then temporal 0->2 (the "
                  "reference's, whatever the run length)")
      ->check(Integer(1))
      ->capture_default_str();
  cmd->add_option("--test-every", options->test_every,
                  "Evaluate the test split every N iterations (0: at the end)")
      ->check(Integer(0))
      ->capture_default_str();
  cmd->add_option("--max-seconds", options->max_seconds,
                  "Stop after this many seconds of training (0 = no limit; a benchmark budget)")
      ->check(Real(0, 1e9))
      ->capture_default_str();
  cmd->add_option("--checkpoint-every", options->checkpoint_every,
                  "Save RUN/checkpoint.bin every N iterations")
      ->check(Integer(0))
      ->capture_default_str();
  cmd->add_option("--background", options->background, "Background grey level in [0,1]")
      ->check(Real(0, 1))
      ->capture_default_str();
  auto learn_background = std::make_shared<bool>(true);
  CLI::Option* learn_background_flag = cmd->add_flag(
      "--learn-background,!--no-learn-background", *learn_background,
      "Learn one background colour with the scene (the default for a new run; a resumed run keeps "
      "what it started with): a sky or backdrop is explained behind the Gaussians instead of by "
      "Gaussians floating at any depth, for HDR colours as a radiance tone mapped like theirs. "
      "--no-learn-background trains on the fixed --background, as the paper does");
  cmd->add_flag("--resume", options->resume,
                "Continue from RUN/checkpoint.bin, exactly as if never stopped, with the run's "
                "own configuration (RUN/config.json): --data and every option not given come "
                "from it; an option given that differs from it is refused before the scene is "
                "read, except --iterations, --threads, --test-every, --checkpoint-every and "
                "--max-seconds");
  CLI::Option* method_flag = cmd->add_option(
         "--method", flags->method,
         fmt::format("Method of the paper's tables: {} (default hdr4dgs; 4dgs when every "
                     "training image has one exposure and the scene has no HDR ground truth, "
                     "with a note: there is no HDR to recover)",
                     fmt::join(baselines::MethodNames(), ", ")))
      ->check(OneOf(TrainMethodNames()))
      ->capture_default_str();
  auto hexplane = AddHexPlaneTrainFlags(cmd);
  cmd->add_option("--tone-mapper", flags->tone_mapper,
                  "Tone mapper (Table 4): dtm, mlp, sigmoid, reinhard or durand (default: the "
                  "method's)")
      ->check(OneOf(method::ToneMapperKinds()));
  CLI::Option* supervision_flag = cmd->add_option("--supervision", flags->supervision,
                  "auto (LDR, plus HDR where the scene has HDR ground truth), ldr, hdr or ldr+hdr")
      ->check(OneOf({"auto", "ldr", "hdr", "ldr+hdr"}))
      ->capture_default_str();
  cmd->add_flag("--no-pixel-branch", flags->no_pixel_branch,
                "Drop the 2D (per-pixel) tone-mapping branch (Table 5)");
  cmd->add_flag("--no-gaussian-branch", flags->no_gaussian_branch,
                "Drop the 3D (per-Gaussian) tone-mapping branch (Table 5): the LDR comes from "
                "the 2D branch alone");
  // Given or not is told by the option's count, never by a sentinel value that a user could type.
  CLI::Option* context_window =
      cmd->add_option("--context-window", flags->context_window,
                      "Radiance-bank rows the context learner reads (Table 6)")
          ->check(Integer(1, 4096))
          ->capture_default_str();
  cmd->add_option("--context-learner", flags->context_learner,
                  "gru, rnn, lstm or transformer (Table 7; default gru)")
      ->check(OneOf({"gru", "rnn", "lstm", "transformer"}));
  CLI::Option* context_size =
      cmd->add_option("--context-size", flags->context_size, "Context vector size d")
          ->check(Integer(1, 64))
          ->capture_default_str();
  cmd->add_flag("--monotone-tone-curves", flags->monotone_curves,
                "Tone-curve MLPs (dtm, mlp) non-decreasing in log exposure by construction "
                "instead of the reference's free ones (docs/history/accuracy.md: no better once "
                "log colours learn at --color-lr's default)");
  cmd->add_flag("--direct-tone-curves", flags->direct_curves,
                "Evaluate the tone-curve MLP per value instead of the per-frame table");
  CLI::Option* hdr_weight_flag =
      cmd->add_option("--hdr-weight", flags->hdr_weight, "Weight of the HDR term (alpha)")
      ->check(Real(0, 1e6))
      ->capture_default_str();
  cmd->add_option_function<double>(
         "--color-lr",
         [options](double lr) {
           options->optimization.f_dc_lr = lr;
           options->optimization.f_dc_lr_log_hdr = lr;
         },
         "Learning rate of the colours' DC term (default: the reference's 2.5e-3 for LDR "
         "colours, 0.04 for log-HDR colours, which span about ten log units where LDR colours "
         "span one: slower, the tone curve squeezes the HDR instead; docs/history/accuracy.md)")
      ->check(Real(1e-9, 10));
  CLI::Option* pixel_log_epsilon_flag =
      cmd->add_option("--pixel-log-epsilon", flags->pixel_log_epsilon,
                      "Floor of the pixel branch's log(HDR + eps) (default: the reference's 1e-5 "
                      "under LDR supervision alone, 1e-8 when an HDR term sets the raster's units: "
                      "at 1e-5 of the target's maximum the darkest pixels the brackets record "
                      "look black to the pixel branch; docs/history/accuracy.md)")
          ->check(Real(1e-30, 1));
  cmd->add_option("--hdr-target", flags->hdr_target,
                  "Target of the HDR term: image-max (the reference: mu-law, mu 5000, of each "
                  "image over its own maximum) or scene-log (mu 1e6, one maximum for the whole "
                  "scene: a constant scale over time, dark regions weighed like bright ones) or aligned "
                  "(the reference's target, the render scaled to it per image by the median "
                  "ratio first: the term fixes the HDR's shape, the LDR terms its scale)")
      ->check(CLI::IsMember({"image-max", "scene-log", "aligned"}));
  CLI::Option* no_hdr_geometry_flag = cmd->add_flag(
      "--no-hdr-geometry", flags->no_hdr_geometry,
      "The HDR term trains the colours only: its gradient does not reach the means, covariances "
      "and opacities (nor the densification statistics), which follow the LDR terms alone. "
      "Under LDR+HDR it recovers about half of the held-out LDR the HDR term otherwise costs, "
      "and gives up part of its HDR gain (docs/history/accuracy.md). Needs an LDR term");
  CLI::Option* hdr_head_flag = cmd->add_flag(
      "--hdr-head", flags->hdr_head,
      "LDR+HDR as an HDR head (not the paper's joint training): train on the LDR images exactly "
      "as --supervision ldr does, then fit a log-radiance offset per Gaussian, used by the HDR "
      "output only, to the HDR ground truth with everything else frozen. The LDR output is LDR "
      "alone's bit for bit, the HDR gains most of the joint term's accuracy "
      "(docs/history/accuracy.md). Needs --supervision ldr+hdr (or auto on a scene with HDR "
      "ground truth). "
      "With --resume it also turns a --supervision ldr run into such a run, whose loop it has "
      "already trained, and fits the head");
  CLI::Option* hdr_head_iterations_flag =
      cmd->add_option("--hdr-head-iterations", flags->hdr_head_iterations,
                      "Steps of the HDR head's fit (one training view each; default: half of "
                      "--iterations)")
          ->check(Integer(1, 100000000));
  cmd->callback([cmd, options, data, out, flags, context_window, context_size, config,
                 list_configs, data_flag, out_flag, method_flag, supervision_flag,
                 hdr_weight_flag, pixel_log_epsilon_flag, learn_background,
                 learn_background_flag, no_hdr_geometry_flag, hdr_head_flag,
                 hdr_head_iterations_flag, hexplane] {
    if (*list_configs) {
      ListTrainConfigs();
      return;
    }
    if (out_flag->count() == 0) Fail("train: --out is required");
    if (TrainHexPlaneIfAsked(cmd, flags->method, *hexplane)) return;  // the grid family
    // --resume: the run's recorded options, the flags given now over them (ResumedOptions).
    std::optional<method::TrainOptions> saved;
    if (options->resume) {
      const std::string record = (std::filesystem::path(*out) / "config.json").string();
      saved = method::TrainOptions::FromJson(method::ReadSavedRunConfig(*out), record);
    }
    if (data_flag->count() == 0 && !saved)
      Fail("train: --data is required (a resumed run takes its own from RUN/config.json)");
    const auto given = [cmd](const std::string& flag) {
      return cmd->get_option(flag)->count() > 0;
    };
    if (!config->empty()) {
      method::ApplyTrainConfig(method::ReadTrainConfig(*config), "--config " + *config, given,
                               saved ? &*saved : options.get());
    }
    options->data = *data;
    options->out = *out;
    if (learn_background_flag->count() > 0) options->learn_background = *learn_background;
    // The colour model and supervision: the method's preset (a resumed run's own), then the
    // flags given.
    method::HdrTrainingOptions hdr =
        saved && method_flag->count() == 0 ? saved->hdr : baselines::MethodPreset(flags->method);
    const bool window_given = context_window->count() > 0, size_given = context_size->count() > 0;
    const bool tunes_tone_mapper = !flags->tone_mapper.empty() || window_given ||
                                   !flags->context_learner.empty() || size_given ||
                                   flags->direct_curves || flags->monotone_curves;
    if (tunes_tone_mapper && !hdr.tone_mapper) {
      Fail("--method {} has no tone mapper, so tone-mapper options do not apply", hdr.method);
    }
    if (hdr.tone_mapper) {
      if (!flags->tone_mapper.empty()) hdr.tone_mapper->kind = flags->tone_mapper;
      if (window_given) hdr.tone_mapper->context_window = flags->context_window;
      if (!flags->context_learner.empty())
        hdr.tone_mapper->context_learner = flags->context_learner;
      if (size_given) hdr.tone_mapper->context_size = flags->context_size;
      if (flags->direct_curves) hdr.tone_mapper->tabulated = false;
      if (flags->monotone_curves) hdr.tone_mapper->monotone_curves = true;
    }
    if ((!saved || supervision_flag->count() > 0) &&
        (flags->supervision != "auto" || hdr.supervision == method::Supervision::kAuto))
      hdr.supervision = method::ParseSupervision(flags->supervision, "--supervision");
    if (flags->no_pixel_branch) hdr.pixel_branch = false;
    if (flags->no_gaussian_branch) hdr.gaussian_branch = false;
    if (hdr_weight_flag->count() > 0) hdr.hdr_weight = flags->hdr_weight;
    if (pixel_log_epsilon_flag->count() > 0) hdr.pixel_log_epsilon = flags->pixel_log_epsilon;
    if (!flags->hdr_target.empty())
      hdr.hdr_target = method::ParseHdrTarget(flags->hdr_target, "--hdr-target");
    if (flags->no_hdr_geometry) hdr.hdr_geometry = false;
    if (flags->hdr_head) {
      // A finished LDR-alone run given --hdr-head becomes the ldr+hdr run with a head whose loop
      // it already trained (AcceptAddedHdrHead).
      if (saved && !saved->hdr.hdr_head && supervision_flag->count() == 0 &&
          hdr.supervision == method::Supervision::kLdr)
        hdr.supervision = method::Supervision::kLdrHdr;
      hdr.hdr_head = true;
    }
    if (hdr_head_iterations_flag->count() > 0) {
      if (!hdr.hdr_head) Fail("train: --hdr-head-iterations needs --hdr-head");
      hdr.hdr_head_iterations = flags->hdr_head_iterations;
    }
    if (std::string p = hdr.Validate(); !p.empty()) Fail("train: {}", p);
    options->hdr = hdr;
    // Nothing HDR asked for: a scene with one exposure and no HDR truth trains plain 4DGS (a
    // resumed run trains what it started with).
    const bool asked_for_hdr = method_flag->count() > 0 || tunes_tone_mapper ||
                               supervision_flag->count() > 0 || flags->no_pixel_branch ||
                               flags->no_gaussian_branch || hdr_weight_flag->count() > 0 ||
                               pixel_log_epsilon_flag->count() > 0 ||
                               no_hdr_geometry_flag->count() > 0 || hdr_head_flag->count() > 0;
    if (!asked_for_hdr && !saved) options->when_nothing_hdr = baselines::MethodPreset("4dgs");
    const method::TrainSummary s =
        method::Train(saved ? ResumedOptions(*saved, *options, given) : *options);
    fmt::print("train: {} iterations in {:.1f} s, {} Gaussians; test {}\n", s.iterations,
               s.train_seconds, s.gaussians, s.test_metrics.dump());
  });
}

}  // namespace hdr4d::cli
