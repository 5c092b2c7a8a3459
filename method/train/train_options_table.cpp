#include "method/train/train_options_table.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "method/tonemap/tone_mapper_registry.h"

namespace hdr4d::method {
namespace {

using Json = nlohmann::json;
constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();
constexpr double kDoubleMax = std::numeric_limits<double>::max();

Json Discarded() { return Json(Json::value_t::discarded); }

template <typename T>
constexpr OptionType TypeOf() {
  if constexpr (std::is_same_v<T, int>) return OptionType::kInt;
  else if constexpr (std::is_same_v<T, std::int64_t>) return OptionType::kInt64;
  else if constexpr (std::is_same_v<T, std::uint64_t>) return OptionType::kUint64;
  else if constexpr (std::is_same_v<T, double>) return OptionType::kDouble;
  else if constexpr (std::is_same_v<T, float>) return OptionType::kFloat;
  else if constexpr (std::is_same_v<T, bool>) return OptionType::kBool;
  else {
    static_assert(std::is_same_v<T, std::string>, "a member type the table does not know");
    return OptionType::kText;
  }
}

// How a row reads and writes its member: the type, and JSON of that type both ways.
struct Access {
  OptionType type;
  std::function<Json(const TrainOptions&)> get;
  std::function<void(TrainOptions*, const Json&)> set;
};

// The member `m` of the struct `pick` selects (pick works on const and mutable options alike).
template <typename T, typename Struct, typename Pick>
Access Member(Pick pick, T Struct::*m) {
  return {TypeOf<T>(), [pick, m](const TrainOptions& o) { return Json(pick(o).*m); },
          [pick, m](TrainOptions* o, const Json& v) { pick(*o).*m = v.get<T>(); }};
}
template <typename T>
Access Top(T TrainOptions::*m) {
  return Member([](auto& o) -> auto& { return o; }, m);
}
template <typename T>
Access Opt(T OptimizationOptions::*m) {
  return Member([](auto& o) -> auto& { return o.optimization; }, m);
}
template <typename T>
Access Init(T InitOptions::*m) {
  return Member([](auto& o) -> auto& { return o.init; }, m);
}
template <typename T>
Access Hdr(T HdrTrainingOptions::*m) {
  return Member([](auto& o) -> auto& { return o.hdr; }, m);
}
// A field of the method's tone mapper: null when it has none; setting one needs one.
template <typename T>
Access Tone(T ToneMapperConfig::*m) {
  return {TypeOf<T>(),
          [m](const TrainOptions& o) {
            return o.hdr.tone_mapper ? Json((*o.hdr.tone_mapper).*m) : Json(nullptr);
          },
          [m](TrainOptions* o, const Json& v) {
            if (!o->hdr.tone_mapper) {
              Fail("--method {} has no tone mapper, so tone-mapper options do not apply",
                   o->hdr.method);
            }
            (*o->hdr.tone_mapper).*m = v.get<T>();
          }};
}
// An enum recorded by name.
template <typename E>
Access Named(E HdrTrainingOptions::*m, const char* (*name)(E), E (*parse)(const std::string&, const std::string&)) {
  return {OptionType::kText, [m, name](const TrainOptions& o) { return Json(name(o.hdr.*m)); },
          [m, parse](TrainOptions* o, const Json& v) {
            o->hdr.*m = parse(v.get<std::string>(), "config.json");
          }};
}

ValueRange TypeRange(OptionType type) {
  switch (type) {
    case OptionType::kInt:
    case OptionType::kInt64:
      return ValueRange::Integer(std::numeric_limits<std::int64_t>::min(),
                                 std::numeric_limits<std::int64_t>::max());
    case OptionType::kUint64:
      return ValueRange::Integer(0, std::numeric_limits<std::int64_t>::max());
    default:
      return ValueRange::AnyReal();
  }
}

// One row, written as a chain: Row(key, member).Flag(...).Range(...).Config(...).
class Row {
 public:
  Row(std::string key, Access access) {
    r_.key = std::move(key);
    r_.type = access.type;
    r_.range = TypeRange(access.type);
    r_.get = std::move(access.get);
    r_.set = std::move(access.set);
  }
  Row& Flag(std::string flag, std::string help) {
    r_.flag = std::move(flag);
    r_.help = std::move(help);
    return *this;
  }
  // A flag without a value that sets the member to `value` (--no-pixel-branch: false).
  Row& Switch(std::string flag, Json value, std::string help) {
    r_.switch_value = std::move(value);
    return Flag(std::move(flag), std::move(help));
  }
  Row& Negatable(std::string off_flag) {
    r_.off_flag = std::move(off_flag);
    return *this;
  }
  Row& Range(ValueRange range) {
    r_.range = range;
    return *this;
  }
  Row& Choices(std::function<std::vector<std::string>()> choices) {
    r_.choices = std::move(choices);
    return *this;
  }
  Row& Choices(std::vector<std::string> choices) {
    return Choices([choices] { return choices; });
  }
  Row& Names(std::string what) {
    r_.what = std::move(what);
    return *this;
  }
  Row& ShowDefault() {
    r_.show_default = true;
    return *this;
  }
  Row& UnsetWhen(Unset unset) {
    r_.unset = unset;
    return *this;
  }
  Row& Config(std::string name) {
    r_.config_name = std::move(name);
    return *this;
  }
  Row& MayChangeOnResume() {
    r_.may_change_on_resume = true;
    return *this;
  }
  Row& NotReadBack() {
    r_.from_record = false;
    return *this;
  }
  Row& InsideAnother() {
    r_.recorded = false;
    r_.from_record = false;
    return *this;
  }
  Row& IfMissing(Json value) {
    r_.if_missing = std::move(value);
    return *this;
  }
  Row& Nullable() {
    r_.nullable = true;
    return *this;
  }
  Row& AcceptsAuto() {
    r_.accepts_auto = true;
    return *this;
  }
  Row& AsksForHdr() {
    r_.asks_for_hdr = true;
    return *this;
  }
  Row& Target(OptionTarget target) {
    r_.target = target;
    return *this;
  }
  Row& WhenGiven(std::function<void(TrainOptions*, const Json&)> set_given) {
    r_.set_given = std::move(set_given);
    return *this;
  }
  Row& Read(std::function<void(TrainOptions*, const JsonField&, const std::string&)> read) {
    r_.read = std::move(read);
    return *this;
  }
  operator TrainOption() const { return r_; }  // NOLINT: rows read as a list

 private:
  TrainOption r_;
};

// A tone-mapper option given on the command line: laid over the method's tone mapper, recorded
// inside its object (hdr.tone_mapper).
Row ToneRow(std::string field, Access access) {
  Row row("hdr.tone_mapper." + field, std::move(access));
  row.Target(OptionTarget::kToneMapper).InsideAnother().AsksForHdr();
  return row;
}

Row HdrRow(std::string field, Access access) {
  Row row("hdr." + field, std::move(access));
  row.Target(OptionTarget::kHdr);
  return row;
}

Access DataAccess() {
  return {OptionType::kText,
          [](const TrainOptions& o) {
            return Json(std::filesystem::absolute(o.data).string());
          },
          [](TrainOptions* o, const Json& v) { o->data = v.get<std::string>(); }};
}

// A switch the run decides when it is not given (std::optional<bool>): unset is not recorded
// (a caller's own look at the options; a run records what it decided).
template <typename Struct, typename Pick>
Access OptionalBool(Pick pick, std::optional<bool> Struct::*m) {
  return {OptionType::kBool,
          [pick, m](const TrainOptions& o) {
            const std::optional<bool>& v = pick(o).*m;
            return v ? Json(*v) : Discarded();
          },
          [pick, m](TrainOptions* o, const Json& v) { pick(*o).*m = v.get<bool>(); }};
}
Access LearnBackgroundAccess() {
  return OptionalBool([](auto& o) -> auto& { return o; }, &TrainOptions::learn_background);
}
Access CloneOpacityCorrectionAccess() {
  return OptionalBool([](auto& o) -> auto& { return o.optimization; },
                      &OptimizationOptions::clone_opacity_correction);
}

// --color-lr: the DC rate of LDR and of log-HDR colours alike.
Access ColorLrAccess() {
  return {OptionType::kDouble, [](const TrainOptions&) { return Discarded(); },
          [](TrainOptions* o, const Json& v) {
            o->optimization.f_dc_lr = v.get<double>();
            o->optimization.f_dc_lr_log_hdr = v.get<double>();
          }};
}

Access PixelLogEpsilonAccess() {
  return {OptionType::kFloat,
          [](const TrainOptions& o) {
            return o.hdr.pixel_log_epsilon ? Json(*o.hdr.pixel_log_epsilon) : Json(nullptr);
          },
          [](TrainOptions* o, const Json& v) {
            if (v.is_null()) {
              o->hdr.pixel_log_epsilon.reset();
            } else {
              o->hdr.pixel_log_epsilon = v.get<float>();
            }
          }};
}

Access ColorModeAccess() {
  return {OptionType::kText,
          [](const TrainOptions& o) {
            return Json(o.hdr.color_mode == ColorMode::kLdr ? "ldr" : "log_hdr");
          },
          [](TrainOptions* o, const Json& v) {
            o->hdr.color_mode = v.get<std::string>() == "ldr" ? ColorMode::kLdr : ColorMode::kLogHdr;
          }};
}

// The method's tone mapper as its own object (ToneMapperConfig::ToJson), or null for none.
Access ToneMapperAccess() {
  return {OptionType::kJson,
          [](const TrainOptions& o) {
            return o.hdr.tone_mapper ? o.hdr.tone_mapper->ToJson() : Json(nullptr);
          },
          [](TrainOptions* o, const Json& v) {
            if (v.is_null()) {
              o->hdr.tone_mapper.reset();
            } else {
              o->hdr.tone_mapper = ToneMapperConfig::FromJson(v, "tone mapper");
            }
          }};
}

std::vector<std::string> SupervisionNames() {
  std::vector<std::string> names;
  for (Supervision s :
       {Supervision::kAuto, Supervision::kLdr, Supervision::kHdr, Supervision::kLdrHdr})
    names.push_back(SupervisionName(s));
  return names;
}

std::vector<std::string> HdrTargetNames() {
  std::vector<std::string> names;
  for (HdrTarget t : {HdrTarget::kImageMax, HdrTarget::kSceneLog, HdrTarget::kAligned})
    names.push_back(HdrTargetName(t));
  return names;
}

// --iterations: a count, or "auto" (the run length stays the schedules' and becomes a cap; the
// run stops when its loss has stopped improving: OptimizationOptions::stop_window).
Access IterationsAccess() {
  return {OptionType::kInt,
          [](const TrainOptions& o) { return Json(o.optimization.iterations); },
          [](TrainOptions* o, const Json& v) {
            OptimizationOptions& opt = o->optimization;
            if (v.is_string()) {  // "auto", checked by the row
              if (opt.stop_window == 0) opt.stop_window = OptimizationOptions::kDefaultStopWindow;
            } else {
              opt.iterations = v.get<int>();
            }
          }};
}

// The run: its scene, length, seed, threads, image size, batch and Gaussians.
std::vector<TrainOption> RunRows() {
  using O = OptimizationOptions;
  const auto count = [](std::int64_t min) { return ValueRange::Integer(min); };
  return {
      Row("data", DataAccess())
          .Flag("--data", "Scene folder (with --resume: the run's own by default)")
          .Names("a scene folder"),
      Row("exposure_unit", Top(&TrainOptions::exposure_unit))
          .Flag("--exposure-unit", kExposureUnitHelp)
          .Choices(std::vector<std::string>{ExposureUnitName(ExposureUnit::kSeconds),
                                            ExposureUnitName(ExposureUnit::kStops)})
          .ShowDefault()
          .Config("exposure_unit")
          .IfMissing(ExposureUnitName(ExposureUnit::kSeconds)),  // runs from before: seconds
      Row("optimization.iterations", IterationsAccess())
          .Flag("--iterations",
                "Training iterations. The schedules (densification window, position "
                "learning-rate decay, opacity resets) follow it: "
                "the reference's values are those of 20000 iterations; a flag given below "
                "wins over the scaling. auto: the schedules of the default length, and stop "
                "once the training loss has stopped improving (--stop-window, "
                "--stop-tolerance); results.json says when and why. Not given, on a scene "
                "with a val split: as auto with --stop-on-val")
          .Range(count(1))
          .AcceptsAuto()
          .ShowDefault()
          .Config("iterations")
          .MayChangeOnResume(),
      Row("seed", Top(&TrainOptions::seed))
          .Flag("--seed", "Random seed (same seed and threads: identical runs)")
          .ShowDefault(),
      Row("threads", Top(&TrainOptions::threads))
          .Flag("--threads", "Threads (0 = all cores)")
          .Range(ValueRange::Integer(0, 4096))
          .ShowDefault()
          .MayChangeOnResume()
          .NotReadBack(),  // a resumed run uses this machine's cores unless told
      Row("resolution", Top(&TrainOptions::resolution))
          .Flag("--resolution",
                "Train at 1/R of the images' size: every image (LDR and HDR, train and test) "
                "is box-averaged over R x R pixels on load and the intrinsics divided by R; "
                "R must divide the images' width and height (the reference: 2 for "
                "HDR-4D-Syn, 4 for HDR-4D-Real). `hdr4d render` uses the run's R")
          .Range(ValueRange::Integer(1, 1 << 16))
          .ShowDefault()
          .Config("resolution"),
      Row("optimization.batch_size", Opt(&O::batch_size))
          .Flag("--batch-size",
                "Views per iteration (the reference's batch_size): the loss is their mean, "
                "one optimiser step per batch, densification statistics as the reference "
                "accumulates them; --iterations counts batches")
          .Range(ValueRange::Integer(1, 4096))
          .ShowDefault()
          .Config("batch_size"),
      Row("optimization.max_gaussians", Opt(&O::max_gaussians))
          .Flag("--max-gaussians",
                "Gaussian budget (the reference's densify_until_num_points): densification "
                "never takes the count past N, keeping the clone/split candidates with the "
                "largest gradients; 0 = no budget (default: 2 x the pixels of one training "
                "view up to 200 x 200 and 2 x side x 200 beyond, half that for one moving "
                "camera (--reference: 2 x the pixels); a static scene one view's pixels per "
                "view of content, the point cloud's points any camera sees over those one "
                "camera sees (--reference, or no cloud in view: 2 x every view's pixels); at "
                "least 32768; BENCHMARKS.md). An N "
                "given here also caps the initial point cloud: a larger point3d.ply is "
                "subsampled to N points, evenly over the file's order, and a scene without "
                "one starts from at most N random points (the default budget leaves both "
                "whole); N is 0 or at least 4")
          .Range(ValueRange::Integer(0, std::int64_t{1} << 40))
          .UnsetWhen(Unset::kNegative)
          .Config("max_gaussians"),
      Row("init.num_random_points", Init(&InitOptions::num_random_points))
          .Flag("--random-points", "Initial random points when the scene has no point3d.ply")
          .Range(ValueRange::Integer(4, 100'000'000))
          .ShowDefault(),
  };
}

// The schedules (unset: they follow the run length, ARCHITECTURE §4 "Optimisation").
std::vector<TrainOption> ScheduleRows() {
  using O = OptimizationOptions;
  const auto count = [](std::int64_t min) { return ValueRange::Integer(min); };
  return {
      Row("optimization.densify_from", Opt(&O::densify_from))
          .Flag("--densify-from",
                "First densification iteration (default: 2.5% of --iterations, the "
                "reference's 500 of 20000)")
          .Range(count(0))
          .UnsetWhen(Unset::kNegative)
          .Config("densify_from"),
      Row("optimization.densify_until", Opt(&O::densify_until))
          .Flag("--densify-until",
                "Last densification iteration (default: 75% of --iterations, 15000 of 20000)")
          .Range(count(0))
          .UnsetWhen(Unset::kNegative)
          .Config("densify_until"),
      Row("optimization.densification_interval", Opt(&O::densification_interval))
          .Flag("--densification-interval",
                "Iterations between densifications (the reference's, whatever the run length)")
          .Range(count(1))
          .ShowDefault()
          .Config("densification_interval"),
      Row("optimization.densify_grad_threshold", Opt(&O::densify_grad_threshold))
          .Flag("--densify-grad-threshold",
                "Clone/split when the mean NDC screen gradient reaches this (default: the "
                "reference's 2e-4 at 400 px, times 400 / the image size: 8e-4 at 100 px)")
          .Range(ValueRange::Real(0, kDoubleMax, /*open_min=*/true))
          .UnsetWhen(Unset::kNegative)
          .Config("densify_grad_threshold"),
      Row("optimization.position_lr_max_steps", Opt(&O::position_lr_max_steps))
          .Flag("--position-lr-steps",
                "Iterations over which the position learning rate decays (default: 75% of "
                "--iterations, 15000 of 20000)")
          .Range(count(1))
          .UnsetWhen(Unset::kNegative)
          .Config("position_lr_max_steps"),
      Row("optimization.opacity_reset_interval", Opt(&O::opacity_reset_interval))
          .Flag("--opacity-reset-interval",
                "Iterations between opacity resets while densifying (default: the reference's "
                "3000 whatever --iterations: more frequent resets leave no time to recover)")
          .Range(count(1))
          .UnsetWhen(Unset::kNegative)
          .Config("opacity_reset_interval"),
      Row("optimization.sh_increase_interval", Opt(&O::sh_increase_interval))
          .Flag("--sh-increase-interval",
                "Iterations per colour degree step, spatial 0->3 then temporal 0->2, whatever "
                "the run length (default: the reference's 1000; 500 with "
                "--clone-opacity-correction reaches a static ring's quality sooner but ended "
                "lower on a real capture at 20000 iterations)")
          .Range(count(1))
          .UnsetWhen(Unset::kNegative)
          .Config("sh_increase_interval"),
  };
}

// How often the run reports and saves, how long it may take, and its background.
std::vector<TrainOption> CadenceRows() {
  const auto count = [](std::int64_t min) { return ValueRange::Integer(min); };
  return {
      Row("test_every", Top(&TrainOptions::test_every))
          .Flag("--test-every",
                "Evaluate the test split every N iterations (0: at the end), before that "
                "iteration's densification as the reference does; RUN/results.json's "
                "test_curve holds each evaluation's metrics, iteration and training seconds")
          .Range(count(0))
          .ShowDefault()
          .MayChangeOnResume(),
      Row("max_seconds", Top(&TrainOptions::max_seconds))
          .Flag("--max-seconds",
                "Stop after this many seconds of training (0 = no limit; a benchmark budget)")
          .Range(ValueRange::Real(0, 1e9))
          .ShowDefault()
          .MayChangeOnResume(),
      Row("checkpoint_every", Top(&TrainOptions::checkpoint_every))
          .Flag("--checkpoint-every", "Save RUN/checkpoint.bin every N iterations")
          .Range(count(0))
          .ShowDefault()
          .MayChangeOnResume(),
      Row("background", Top(&TrainOptions::background))
          .Flag("--background", "Background grey level in [0,1]")
          .Range(ValueRange::Real(0, 1))
          .ShowDefault(),
      Row("learn_background", LearnBackgroundAccess())
          .Switch("--learn-background", true,
                  "Learn one background colour with the scene (the default for a new run; a "
                  "resumed run keeps what it started with): a sky or backdrop is explained "
                  "behind the Gaussians instead of by Gaussians floating at any depth, for HDR "
                  "colours as a radiance tone mapped like theirs. --no-learn-background trains "
                  "on the fixed --background, as the paper does")
          .Negatable("--no-learn-background")
          .IfMissing(false),
  };
}

// The learned per-camera correction (method/tonemap/camera_correction.h; issue 52). Runs from
// before the option trained without it.
std::vector<TrainOption> CameraCorrectionRows() {
  return {
      Row("camera_correction", Top(&TrainOptions::camera_correction))
          .Switch("--camera-correction", true,
                  "Learn a log gain per colour channel for each training camera, added to the "
                  "tone curve's input and regularised towards none (not in the paper): cameras "
                  "of a rig that differ in gain or white balance. Held-out times of a training "
                  "camera render with its gains, other cameras with none. Needs a tone mapper")
          .IfMissing(false),
      Row("camera_correction_weight", Top(&TrainOptions::camera_correction_weight))
          .Flag("--camera-correction-weight",
                "Weight of the correction's pull towards no gain: weight x |d|^2 per camera "
                "in the step")
          .Range(ValueRange::Real(0, 1e6))
          .ShowDefault()
          .IfMissing(0.01),
      Row("camera_correction_lr", Top(&TrainOptions::camera_correction_lr))
          .Flag("--camera-correction-lr", "Adam's learning rate on the correction's log gains")
          .Range(ValueRange::Real(1e-9, 10))
          .ShowDefault()
          .IfMissing(0.002),
  };
}

// Doing less where the scene does not need it (issue 55), and --reference, which does none of
// it: the paper-faithful configuration. Kept together.
std::vector<TrainOption> SpeedRows() {
  using O = OptimizationOptions;
  return {
      Row("reference", Top(&TrainOptions::reference))
          .Switch("--reference", true,
                  "The paper-faithful configuration: dense Adam, every iteration asked for "
                  "(the defaults before issue 55, bit for bit; the radiance bank's unseen rows "
                  "read as zeros); refused with an option below")
          .IfMissing(false)
          .WhenGiven([](TrainOptions* o, const Json&) {
            o->reference = true;
            o->optimization.visible_adam = false;
            o->optimization.color_bands_by_need = false;
            o->optimization.coarse_to_fine = 0;
            o->optimization.prune_contribution = 0.0;
            o->optimization.prune_radiance_share = false;
            o->optimization.clone_opacity_correction = false;
            // A tone mapper given later gets it in ResolveTrainRequest.
            if (o->hdr.tone_mapper) o->hdr.tone_mapper->unseen_rows = "zero";
          }),
      Row("optimization.visible_adam", Opt(&O::visible_adam))
          .Switch("--visible-adam", true,
                  "Step Adam only on the Gaussians a step saw, catching their moments' decay up "
                  "exactly when they are seen again (not dense Adam: the drift of an unseen "
                  "Gaussian along its momentum is skipped). --dense-adam: every Gaussian, every "
                  "step, as the paper")
          .Negatable("--dense-adam")
          .IfMissing(false)
          .Config("visible_adam"),
      Row("optimization.stop_window", Opt(&O::stop_window))
          .Flag("--stop-window",
                "Iterations per window of --iterations auto: stop when the mean training loss "
                "of the last window improved by less than --stop-tolerance on the window "
                "before, both after densification ended (0: run every iteration; auto: 1000)")
          .Range(ValueRange::Integer(0, kIntMax))
          .IfMissing(0)
          .MayChangeOnResume(),
      Row("optimization.stop_tolerance", Opt(&O::stop_tolerance))
          .Flag("--stop-tolerance",
                "Relative improvement of the windowed training loss under which "
                "--iterations auto stops")
          .Range(ValueRange::Real(0, 1))
          .ShowDefault()
          .IfMissing(O::kDefaultStopTolerance)
          .MayChangeOnResume(),
      Row("optimization.stop_on_val", Opt(&O::stop_on_val))
          .Switch("--stop-on-val", true,
                  "With --iterations auto: decide the stop on the scene's val split "
                  "(transforms_val.json or val_filenames), scored every --stop-window "
                  "iterations, instead of the training loss: stop once 3 evaluations in a row "
                  "lowered the val views' error by less than --stop-tolerance on the best so "
                  "far (the last model is kept). Needs a val split. The default on a scene with "
                  "one when no run length (--iterations, --stop-window, a configuration's "
                  "iterations) is given. --no-stop-on-val: the training loss decides (with "
                  "--stop-window 0: every iteration asked for; also on resume)")
          .Negatable("--no-stop-on-val")
          .IfMissing(false)
          .MayChangeOnResume(),
      Row("optimization.grow_on_val", Opt(&O::grow_on_val))
          .Switch("--grow-on-val", true,
                  "With --stop-on-val: the val evaluations also decide how far the model grows. "
                  "From the first one, while densifying, that did not improve on the best so "
                  "far, the Gaussian count stays at or under its count then (results.json: "
                  "growth_stopped). --no-grow-on-val: only --max-gaussians caps it")
          .Negatable("--no-grow-on-val")
          .IfMissing(false)
          .Config("grow_on_val"),
      Row("optimization.keep_best_val", Opt(&O::keep_best_val))
          .Switch("--keep-best-val", true,
                  "With --stop-on-val: when the val views stop the run, end on the model of "
                  "their best evaluation (kept in RUN/best_val.bin until then) instead of the "
                  "last one; a run that reaches its length keeps its last model. results.json: "
                  "stopped.model_iteration. --no-keep-best-val: the last model")
          .Negatable("--no-keep-best-val")
          .IfMissing(false)
          .Config("keep_best_val"),
  };
}

// Doing less per iteration (issue 55), after SpeedRows: off under --reference, measured and not
// the default (docs/history/time-to-quality.md).
std::vector<TrainOption> LessWorkRows() {
  using O = OptimizationOptions;
  return {
      Row("optimization.coarse_to_fine", Opt(&O::coarse_to_fine))
          .Flag("--coarse-to-fine",
                "Iterations at the start that train on reduced images: 1/4 of the size over "
                "the first half of them, 1/2 over the rest (any size: the last columns and "
                "rows the factor leaves over sit out; 0: full size throughout, as the paper)")
          .Range(ValueRange::Integer(0, kIntMax))
          .IfMissing(0)
          .Config("coarse_to_fine"),
      Row("optimization.prune_contribution", Opt(&O::prune_contribution))
          .Flag("--prune-contribution",
                "At each densification also prune the Gaussians seen since the last one whose "
                "largest blending weight (alpha x transmittance) at any pixel of those views "
                "stayed below this (0: off, as the paper; not within densify-from iterations "
                "of an opacity reset)")
          .Range(ValueRange::Real(0, 0.999))
          .IfMissing(0.0)
          .Config("prune_contribution"),
      Row("optimization.prune_radiance_share", Opt(&O::prune_radiance_share))
          .Switch("--prune-radiance-share", true,
                  "With --prune-contribution: a Gaussian's contribution at a pixel is the larger "
                  "of its blending weight and its part of the pixel's HDR radiance (weight x "
                  "its radiance / the pixel's, per channel), so a faint Gaussian that carries a "
                  "light or a dark region's radiance is kept (methods with HDR colours)")
          .IfMissing(false)
          .Config("prune_radiance_share"),
      Row("optimization.clone_opacity_correction", CloneOpacityCorrectionAccess())
          .Switch("--clone-opacity-correction", true,
                  "At each densification give a clone and its source opacity 1 - sqrt(1 - "
                  "alpha) each, so the two blend as the one did (Rota Bulo et al., ECCV 2024; "
                  "not in the paper, whose clones both keep alpha). Default: off, as the paper; "
                  "--no-clone-opacity-correction says so explicitly")
          .Negatable("--no-clone-opacity-correction")
          .IfMissing(false)
          .Config("clone_opacity_correction"),
      Row("optimization.color_bands_by_need", Opt(&O::color_bands_by_need))
          .Switch("--color-bands-by-need", true,
                  "Start the higher colour bands (SH degrees 1-3, time degrees 1-2) frozen: "
                  "where the reference adds one (every --sh-increase-interval), probe its "
                  "gradient over the next 100 iterations without stepping it and switch it on "
                  "only when the views' gradients agree beyond noise (--color-band-signal); a "
                  "frozen band costs no Adam step. --all-color-bands (the default): every band "
                  "on the reference's schedule, as the paper")
          .Negatable("--all-color-bands")
          .IfMissing(false)
          .Config("color_bands_by_need"),
      Row("optimization.color_band_signal", Opt(&O::color_band_signal))
          .Flag("--color-band-signal",
                "The probe's threshold: over all Gaussians and a band's coefficients, the "
                "squared sum of the band's gradients over the probe's views (after the DC "
                "term's share) against what noise would give (about 1 where the colour does "
                "not follow the band)")
          .Range(ValueRange::Real(0, 1e9))
          .ShowDefault()
          .IfMissing(O::kDefaultColorBandSignal)
          .Config("color_band_signal"),
  };
}

// The colour model's tone mapper and branches, over the method's preset.
std::vector<TrainOption> ToneMappingRows() {
  return {
      ToneRow("kind", Tone(&ToneMapperConfig::kind))
          .Flag("--tone-mapper",
                "Tone mapper (Table 4): dtm, mlp, sigmoid, reinhard or durand (default: the "
                "method's)")
          .Choices(ToneMapperKinds),
      HdrRow("supervision", Named(&HdrTrainingOptions::supervision, SupervisionName,
                                  ParseSupervision))
          .Flag("--supervision",
                "auto (LDR, plus HDR where the scene has HDR ground truth), ldr, hdr or ldr+hdr")
          .Choices(SupervisionNames())
          .ShowDefault()
          .AsksForHdr()
          .WhenGiven([](TrainOptions* o, const Json& v) {
            // auto keeps the method's own (auto for hdr4dgs, ldr for 4dgs, ...).
            if (v != "auto") o->hdr.supervision = ParseSupervision(v.get<std::string>(), "--supervision");
          }),
      HdrRow("pixel_branch", Hdr(&HdrTrainingOptions::pixel_branch))
          .Switch("--no-pixel-branch", false,
                  "Drop the 2D (per-pixel) tone-mapping branch (Table 5)")
          .AsksForHdr(),
      HdrRow("gaussian_branch", Hdr(&HdrTrainingOptions::gaussian_branch))
          .Switch("--no-gaussian-branch", false,
                  "Drop the 3D (per-Gaussian) tone-mapping branch (Table 5): the LDR comes from "
                  "the 2D branch alone")
          .AsksForHdr(),
      ToneRow("context_window", Tone(&ToneMapperConfig::context_window))
          .Flag("--context-window", "Radiance-bank rows the context learner reads (Table 6)")
          .Range(ValueRange::Integer(1, 4096))
          .ShowDefault(),
      ToneRow("context_learner", Tone(&ToneMapperConfig::context_learner))
          .Flag("--context-learner", "gru, rnn, lstm or transformer (Table 7; default gru)")
          .Choices(std::vector<std::string>{"gru", "rnn", "lstm", "transformer"}),
      ToneRow("context_size", Tone(&ToneMapperConfig::context_size))
          .Flag("--context-size", "Context vector size d")
          .Range(ValueRange::Integer(1, 64))
          .ShowDefault(),
      ToneRow("unseen_rows", Tone(&ToneMapperConfig::unseen_rows))
          .Flag("--unseen-bank-rows",
                "How the Dynamic Tone Mapper's context reads a radiance-bank row no training "
                "view writes (a held-out frame's own timestamp on a monocular scene): "
                "interpolate (default) between the nearest written rows in time, or zero, as "
                "before (--reference; BENCHMARKS.md, issue 52)")
          .Choices(std::vector<std::string>{"interpolate", "zero"}),
      ToneRow("monotone_curves", Tone(&ToneMapperConfig::monotone_curves))
          .Switch("--monotone-tone-curves", true,
                  "Tone-curve MLPs (dtm, mlp) non-decreasing in log exposure by construction "
                  "instead of the reference's free ones (BENCHMARKS.md, issue 12: no better "
                  "once log colours learn at --color-lr's default)"),
      ToneRow("tabulated", Tone(&ToneMapperConfig::tabulated))
          .Switch("--direct-tone-curves", false,
                  "Evaluate the tone-curve MLP per value instead of the per-frame table"),
  };
}

// The HDR term and the colours' learning rate.
std::vector<TrainOption> HdrTermRows() {
  return {
      HdrRow("hdr_weight", Hdr(&HdrTrainingOptions::hdr_weight))
          .Flag("--hdr-weight", "Weight of the HDR term (alpha)")
          .Range(ValueRange::Real(0, 1e6))
          .ShowDefault()
          .AsksForHdr(),
      Row("", ColorLrAccess())
          .Flag("--color-lr",
                "Learning rate of the colours' DC term (default: the reference's 2.5e-3 for LDR "
                "colours, 0.04 for log-HDR colours, which span about ten log units where LDR "
                "colours span one: slower, the tone curve squeezes the HDR instead; "
                "BENCHMARKS.md, issue 12)")
          .Range(ValueRange::Real(1e-9, 10))
          .InsideAnother(),  // recorded as optimization.f_dc_lr and f_dc_lr_log_hdr
      HdrRow("pixel_log_epsilon", PixelLogEpsilonAccess())
          .Flag("--pixel-log-epsilon",
                "Floor of the pixel branch's log(HDR + eps) (default: the reference's 1e-5 "
                "under LDR supervision alone, 1e-8 when an HDR term sets the raster's units: "
                "at 1e-5 of the target's maximum the darkest pixels the brackets record "
                "look black to the pixel branch; BENCHMARKS.md, issue 12)")
          .Range(ValueRange::Real(1e-30, 1))
          .Nullable()
          .IfMissing(kReferencePixelLogEpsilon)  // runs from before: the reference's floor
          .AsksForHdr(),
      HdrRow("hdr_target", Named(&HdrTrainingOptions::hdr_target, HdrTargetName, ParseHdrTarget))
          .Flag("--hdr-target",
                "Target of the HDR term: image-max (the reference: mu-law, mu 5000, of each "
                "image over its own maximum) or scene-log (mu 1e6, one maximum for the whole "
                "scene: a constant scale over time, dark regions weighed like bright ones) or "
                "aligned (the reference's target, the render scaled to it per image by the "
                "median ratio first: the term fixes the HDR's shape, the LDR terms its scale)")
          .Choices(HdrTargetNames())
          .IfMissing("image-max"),  // runs from before: the reference's target
      HdrRow("hdr_geometry", Hdr(&HdrTrainingOptions::hdr_geometry))
          .Switch("--no-hdr-geometry", false,
                  "The HDR term trains the colours only: its gradient does not reach the means, "
                  "covariances and opacities (nor the densification statistics), which follow "
                  "the LDR terms alone. Under LDR+HDR it recovers about half of the held-out LDR "
                  "the HDR term otherwise costs, and gives up part of its HDR gain "
                  "(BENCHMARKS.md, issue 12 §3). Needs an LDR term")
          .IfMissing(true)  // runs from before: the HDR term reached the geometry
          .AsksForHdr(),
      HdrRow("hdr_head", Hdr(&HdrTrainingOptions::hdr_head))
          .Switch("--hdr-head", true,
                  "LDR+HDR as an HDR head (not the paper's joint training): train on the LDR "
                  "images exactly as --supervision ldr does, then fit a log-radiance offset per "
                  "Gaussian, used by the HDR output only, to the HDR ground truth with "
                  "everything else frozen. The LDR output is LDR alone's bit for bit, the HDR "
                  "gains most of the joint term's accuracy (BENCHMARKS.md, issue 12 §3). Needs "
                  "--supervision ldr+hdr (or auto on a scene with HDR ground truth). With "
                  "--resume it also turns a --supervision ldr run into such a run, whose loop "
                  "it has already trained, and fits the head")
          .IfMissing(false)
          .AsksForHdr(),
      HdrRow("hdr_head_iterations", Hdr(&HdrTrainingOptions::hdr_head_iterations))
          .Flag("--hdr-head-iterations",
                "Steps of the HDR head's fit (one training view each; default: half of "
                "--iterations)")
          .Range(ValueRange::Integer(1, 100'000'000))
          .UnsetWhen(Unset::kZero)
          .IfMissing(0)
          .WhenGiven([](TrainOptions* o, const Json& v) {
            if (!o->hdr.hdr_head) Fail("train: --hdr-head-iterations needs --hdr-head");
            o->hdr.hdr_head_iterations = v.get<int>();
          }),
  };
}

// What `hdr4d train` takes on the command line, in the order of its help.
std::vector<TrainOption> FlagRows() {
  std::vector<TrainOption> rows;
  for (auto group : {RunRows, ScheduleRows, CadenceRows, SpeedRows, LessWorkRows,
                     CameraCorrectionRows, ToneMappingRows, HdrTermRows}) {
    for (TrainOption& row : group()) rows.push_back(std::move(row));
  }
  return rows;
}

// Recorded in RUN/config.json without a flag: the method's preset, the optimiser's settings
// (a --config file may set a few), the initialisation's.
std::vector<TrainOption> RecordRows() {
  using O = OptimizationOptions;
  const auto rate = [] { return ValueRange::Real(1e-30, 1e30); };
  return {
      Row("optimization.position_lr_init", Opt(&O::position_lr_init))
          .Range(rate())
          .Config("position_lr_init"),
      Row("optimization.position_lr_final", Opt(&O::position_lr_final))
          .Range(rate())
          .Config("position_lr_final"),
      Row("optimization.t_lr_init", Opt(&O::t_lr_init)),  // < 0: position_lr_init's
      Row("optimization.f_dc_lr", Opt(&O::f_dc_lr)),
      Row("optimization.f_dc_lr_log_hdr", Opt(&O::f_dc_lr_log_hdr)),
      Row("optimization.f_rest_lr", Opt(&O::f_rest_lr)),
      Row("optimization.opacity_lr", Opt(&O::opacity_lr)),
      Row("optimization.scaling_lr", Opt(&O::scaling_lr)),
      Row("optimization.rotation_lr", Opt(&O::rotation_lr)),
      Row("optimization.adam_eps", Opt(&O::adam_eps)),
      Row("optimization.lambda_dssim", Opt(&O::lambda_dssim))
          .Range(ValueRange::Real(0, 1))
          .Config("lambda_dssim"),
      Row("optimization.percent_dense", Opt(&O::percent_dense)),
      Row("optimization.prune_opacity", Opt(&O::prune_opacity)),
      Row("init.random_half_extent", Init(&InitOptions::random_half_extent)),
      Row("init.initial_opacity", Init(&InitOptions::initial_opacity)),
      HdrRow("method", Hdr(&HdrTrainingOptions::method)),
      HdrRow("color_mode", ColorModeAccess()).Choices(std::vector<std::string>{"ldr", "log_hdr"}),
      HdrRow("force_static", Hdr(&HdrTrainingOptions::force_static)),
      HdrRow("tone_mapper", ToneMapperAccess())
          .Nullable()
          .Read([](TrainOptions* o, const JsonField& field, const std::string& source) {
            if (field.json().is_null()) {
              o->hdr.tone_mapper.reset();
            } else {
              o->hdr.tone_mapper = ToneMapperConfig::FromJson(field.json(), source);
            }
          }),
  };
}

// `key` below `under` ("hdr.hdr_weight" under "hdr": "hdr_weight"); empty when it is not.
std::string Below(const std::string& key, const std::string& under) {
  if (under.empty()) return key;
  if (key.size() <= under.size() + 1 || key.compare(0, under.size(), under) != 0 ||
      key[under.size()] != '.')
    return "";
  return key.substr(under.size() + 1);
}

}  // namespace

std::string TrainOption::Accepts() const {
  switch (type) {
    case OptionType::kBool:
      return "true or false";
    case OptionType::kText:
      if (choices) return fmt::format("one of {}", fmt::join(choices(), ", "));
      return what.empty() ? "a string" : what;
    case OptionType::kJson:
      return "a JSON value";
    default:
      return accepts_auto ? range.Describe() + " or auto" : range.Describe();
  }
}

std::string TrainOption::Check(const Json& value, bool allow_unset) const {
  if (value.is_null() && nullable) return "";
  if (accepts_auto && value == "auto") return "";
  const bool number = value.is_number() && std::isfinite(value.get<double>());
  const double v = number ? value.get<double>() : 0.0;
  // The member's "not given" value (it then follows the run length, or the iterations).
  const bool unset_value = allow_unset && number && ((unset == Unset::kNegative && v < 0) ||
                                      (unset == Unset::kZero && v == 0));
  bool ok = false;
  switch (type) {
    case OptionType::kInt:
    case OptionType::kInt64:
      ok = number && v == std::floor(v) &&
           (unset_value || range.Contains(v)) &&
           (type != OptionType::kInt || std::abs(v) <= static_cast<double>(kIntMax));
      break;
    case OptionType::kUint64:
      ok = value.is_number_unsigned() ||
           (value.is_number_integer() && value.get<std::int64_t>() >= 0);
      break;
    case OptionType::kDouble:
    case OptionType::kFloat:
      ok = number && (unset_value || range.Contains(v)) &&
           (type != OptionType::kFloat || std::abs(v) <= std::numeric_limits<float>::max());
      break;
    case OptionType::kBool:
      ok = value.is_boolean();
      break;
    case OptionType::kText:
      ok = value.is_string();
      if (ok && choices) {
        ok = false;
        for (const std::string& c : choices()) ok = ok || value == c;
      }
      break;
    case OptionType::kJson:
      ok = true;
      break;
  }
  if (ok) return "";
  return fmt::format("expected {}, got {}", Accepts(),
                     value.is_number() || value.is_string() ? value.dump() : JsonPreview(value));
}

Json TrainOption::SwitchValue(bool off) const {
  return off ? Json(!switch_value.get<bool>()) : switch_value;
}

const std::vector<TrainOption>& TrainOptionTable() {
  static const std::vector<TrainOption> table = [] {
    std::vector<TrainOption> rows = FlagRows();
    for (TrainOption& r : RecordRows()) rows.push_back(std::move(r));
    return rows;
  }();
  return table;
}

const TrainOption* FindTrainOption(const std::string& name) {
  if (name.empty()) return nullptr;
  for (const TrainOption& row : TrainOptionTable()) {
    if (row.key == name || row.flag == name || row.off_flag == name) return &row;
  }
  return nullptr;
}

bool MayChangeOnResume(const std::string& key) {
  const TrainOption* row = FindTrainOption(key);
  return row != nullptr && row->key == key && row->may_change_on_resume;
}

Json RecordTrainOptions(const TrainOptions& options, const std::string& under) {
  Json record = Json::object();
  for (const TrainOption& row : TrainOptionTable()) {
    const std::string key = Below(row.key, under);
    if (!row.recorded || key.empty()) continue;
    Json value = row.get(options);
    if (value.is_discarded()) continue;
    std::string pointer(1, '/');  // "optimization.iterations" -> "/optimization/iterations"
    pointer.append(key);
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    record[Json::json_pointer(pointer)] = std::move(value);
  }
  return record;
}

void ReadTrainOptionsRecord(const Json& record,
                            const std::string& source,
                            const std::string& under,
                            TrainOptions* options) {
  const JsonField top = JsonField(record, source, under).Object();
  for (const TrainOption& row : TrainOptionTable()) {
    const std::string key = Below(row.key, under);
    if (!row.from_record || key.empty()) continue;
    // Down the dotted path: each object on the way must be there (and be an object).
    JsonField parent = top;
    std::string name = key;
    for (std::size_t dot; (dot = name.find('.')) != std::string::npos;) {
      parent = parent[name.substr(0, dot)].Object();
      name = name.substr(dot + 1);
    }
    if (!parent.Has(name) && !row.if_missing.is_discarded()) {
      row.set(options, row.if_missing);  // a run from before the option
    } else if (row.read) {
      row.read(options, parent[name], source);
    } else {
      const JsonField field = parent[name];  // names a missing key
      if (std::string problem = row.Check(field.json()); !problem.empty()) field.Fail(problem);
      row.set(options, field.json());
    }
  }
}

std::string CheckTrainOptionValues(const TrainOptions& options, const std::string& under) {
  for (const TrainOption& row : TrainOptionTable()) {
    const std::string key = Below(row.key, under);
    // Free text (a path) is the command's to check; the tone mapper checks its own fields.
    const bool free_text = row.type == OptionType::kText && !row.choices;
    if (key.empty() || free_text || row.target == OptionTarget::kToneMapper ||
        row.type == OptionType::kJson)
      continue;
    const Json value = row.get(options);
    if (value.is_discarded() || value.is_null()) continue;
    if (std::string problem = row.Check(value); !problem.empty())
      return fmt::format("{}: {}", row.key, problem);
  }
  return "";
}

}  // namespace hdr4d::method
