#include "method/train/train_options_table.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using nlohmann::json;
using testing::ErrorOf;

// Every dotted key of a JSON object's leaves (objects are walked, anything else is a leaf).
void Leaves(const json& j, const std::string& prefix, std::set<std::string>* keys) {
  for (const auto& [name, value] : j.items()) {
    const std::string key = prefix.empty() ? name : prefix + "." + name;
    if (value.is_object() && name != "tone_mapper") {
      Leaves(value, key, keys);
    } else {
      keys->insert(key);
    }
  }
}

TrainOptions Recordable() {
  TrainOptions o;
  o.data = "/scene";
  o.out = "/runs/a";
  o.learn_background = true;
  o.optimization.clone_opacity_correction = false;  // what a run decided (unset: not recorded)
  o.hdr.color_mode = ColorMode::kLogHdr;  // hdr4dgs's colour model, with its tone mapper
  o.hdr.tone_mapper = ToneMapperConfig{};
  return o;
}

// RUN/config.json keeps the keys runs have always recorded (a resumed or rendered old run finds
// what it wrote), no more: the table replaced hand-written ToJson code key for key.
TEST(TrainOptionsTable, RecordsTheKeysRunsHaveAlwaysRecorded) {
  std::set<std::string> keys;
  Leaves(Recordable().ToJson(), "", &keys);
  const std::set<std::string> expected = {
      "data", "exposure_unit", "seed", "threads", "resolution", "test_every", "checkpoint_every",
      "max_seconds", "background", "learn_background", "init.num_random_points",
      "init.random_half_extent",
      "init.initial_opacity", "optimization.iterations", "optimization.batch_size",
      "optimization.position_lr_init", "optimization.position_lr_final",
      "optimization.position_lr_max_steps", "optimization.t_lr_init", "optimization.f_dc_lr",
      "optimization.f_dc_lr_log_hdr", "optimization.f_rest_lr", "optimization.opacity_lr",
      "optimization.scaling_lr", "optimization.rotation_lr", "optimization.adam_eps",
      "optimization.lambda_dssim", "optimization.densify_from", "optimization.densify_until",
      "optimization.densification_interval", "optimization.densify_grad_threshold",
      "optimization.percent_dense", "optimization.opacity_reset_interval",
      "optimization.prune_opacity", "optimization.sh_increase_interval",
      "optimization.max_gaussians", "hdr.method", "hdr.color_mode", "hdr.force_static",
      "hdr.tone_mapper", "hdr.supervision", "hdr.pixel_branch", "hdr.gaussian_branch",
      "hdr.hdr_weight", "hdr.hdr_target", "hdr.hdr_geometry", "hdr.hdr_head",
      "hdr.hdr_head_iterations", "hdr.pixel_log_epsilon",
      // issue 52: the per-camera correction
      "camera_correction", "camera_correction_weight", "camera_correction_lr",
      // issue 55
      "reference", "optimization.visible_adam", "optimization.color_bands_by_need",
      "optimization.color_band_signal", "optimization.stop_window",
      "optimization.stop_tolerance", "optimization.coarse_to_fine",
      "optimization.prune_contribution", "optimization.prune_radiance_share",
      "optimization.stop_on_val", "optimization.grow_on_val",
      "optimization.keep_best_val", "optimization.clone_opacity_correction"};
  EXPECT_EQ(keys, expected);
  // Each value keeps its member's JSON type: a float's exact value, an unsigned seed, nulls.
  const json j = Recordable().ToJson();
  EXPECT_TRUE(j["seed"].is_number_unsigned());
  EXPECT_TRUE(j["optimization"]["iterations"].is_number_integer());
  EXPECT_EQ(j["hdr"]["hdr_weight"], json(0.6f));
  EXPECT_TRUE(j["hdr"]["pixel_log_epsilon"].is_null());
  EXPECT_EQ(j["hdr"]["tone_mapper"], ToneMapperConfig{}.ToJson());
  TrainOptions unset = Recordable();
  unset.learn_background.reset();  // a caller's own look: not recorded
  EXPECT_FALSE(unset.ToJson().contains("learn_background"));
  unset.optimization.clone_opacity_correction.reset();
  EXPECT_FALSE(unset.ToJson()["optimization"].contains("clone_opacity_correction"));
}

TEST(TrainOptionsTable, ARecordReadsBackToTheSameOptions) {
  TrainOptions o = Recordable();
  o.seed = 18446744073709551615ull;
  o.max_seconds = 12.5;
  o.background = 0.3f;
  o.optimization.t_lr_init = -1;  // "as position_lr_init": recorded as it is
  o.hdr.hdr_target = HdrTarget::kSceneLog;
  o.hdr.supervision = Supervision::kLdrHdr;
  o.hdr.pixel_log_epsilon = 3e-7f;
  o.hdr.hdr_head = true;
  o.hdr.hdr_head_iterations = 7;
  o.hdr.tone_mapper->context_window = 9;
  const json record = o.ToJson();
  const TrainOptions back = TrainOptions::FromJson(record, "/runs/a/config.json");
  EXPECT_EQ(back.ToJson(), record);
  EXPECT_EQ(back.threads, 0);  // never taken from the record: this machine's
  EXPECT_EQ(back.hdr.pixel_log_epsilon, 3e-7f);
  EXPECT_EQ(HdrTrainingOptions::FromJson(o.hdr.ToJson(), "x").ToJson(), o.hdr.ToJson());
}

// A record from before hdr_target, hdr_geometry, the HDR head, pixel_log_epsilon and the learned
// background: each reads as what such a run trained with.
TEST(TrainOptionsTable, RecordsOfOlderRunsReadAsTheyTrained) {
  json old = Recordable().ToJson();
  old.erase("learn_background");
  old.erase("reference");
  for (const char* key : {"visible_adam", "stop_window", "stop_tolerance", "coarse_to_fine",
                          "prune_contribution", "prune_radiance_share", "color_bands_by_need",
                          "color_band_signal", "clone_opacity_correction"})
    old["optimization"].erase(key);
  for (const char* key : {"hdr_target", "hdr_geometry", "hdr_head", "hdr_head_iterations",
                          "pixel_log_epsilon"})
    old["hdr"].erase(key);
  const TrainOptions o = TrainOptions::FromJson(old, "/runs/old/config.json");
  EXPECT_EQ(o.learn_background, false);
  EXPECT_FALSE(o.reference);  // runs from before issue 55 trained the paper's way
  EXPECT_FALSE(o.optimization.visible_adam);
  EXPECT_EQ(o.optimization.stop_window, 0);
  EXPECT_EQ(o.optimization.coarse_to_fine, 0);
  EXPECT_EQ(o.optimization.prune_contribution, 0.0);
  EXPECT_FALSE(o.optimization.prune_radiance_share);
  EXPECT_FALSE(o.optimization.color_bands_by_need);  // every band on the reference's schedule
  EXPECT_EQ(o.optimization.clone_opacity_correction, false);  // clones kept their source's opacity
  EXPECT_EQ(o.hdr.hdr_target, HdrTarget::kImageMax);
  EXPECT_TRUE(o.hdr.hdr_geometry);
  EXPECT_FALSE(o.hdr.hdr_head);
  EXPECT_EQ(o.hdr.pixel_log_epsilon, kReferencePixelLogEpsilon);
  // A key every run recorded is required, named with its path.
  json bad = Recordable().ToJson();
  bad["hdr"].erase("hdr_weight");
  EXPECT_NE(ErrorOf([&] { TrainOptions::FromJson(bad, "c.json"); })
                .find("c.json: key 'hdr.hdr_weight' is missing"),
            std::string::npos);
  bad = Recordable().ToJson();
  bad["hdr"]["supervision"] = "some";
  EXPECT_NE(ErrorOf([&] { TrainOptions::FromJson(bad, "c.json"); })
                .find("c.json: key 'hdr.supervision': expected one of auto, ldr, hdr, ldr+hdr, "
                      "got \"some\""),
            std::string::npos);
}

// Issue 51 §24: --hdr-weight's help said [0, 1e+06], then 1e6 failed with "must be >= 0 and
// finite". The range is the table's alone, and so are the words of every check.
TEST(TrainOptionsTable, TheRangeAHelpStatesIsTheOneEveryCheckApplies) {
  TrainOptions o = Recordable();
  o.hdr.hdr_weight = 1e6f;
  EXPECT_EQ(o.Validate(), "");
  o.hdr.hdr_weight = 2e6f;
  const TrainOption* weight = FindTrainOption("--hdr-weight");
  ASSERT_NE(weight, nullptr);
  EXPECT_EQ(weight->Accepts(), "a number in [0, 1e+06]");
  EXPECT_NE(o.Validate().find("hdr.hdr_weight: expected a number in [0, 1e+06], got 2"),
            std::string::npos)
      << o.Validate();
  EXPECT_NE(o.hdr.Validate().find("expected a number in [0, 1e+06]"), std::string::npos);
  // A schedule's "follow the run length" is not a value out of range; a given -1 is.
  const TrainOption* from = FindTrainOption("--densify-from");
  ASSERT_NE(from, nullptr);
  EXPECT_EQ(from->Check(-1), "");
  EXPECT_EQ(from->Check(-1, /*allow_unset=*/false), "expected an integer >= 0, got -1");
  EXPECT_EQ(FindTrainOption("--iterations")->Check(2.5),
            "expected an integer >= 1 or auto, got 2.5");
  EXPECT_EQ(FindTrainOption("--threads")->Check("4"),
            "expected an integer in [0, 4096], got \"4\"");
}

TEST(TrainOptionsTable, EveryFlagIsOneRowWithHelpAndItsValues) {
  std::set<std::string> flags, keys;
  TrainOptions defaults;
  defaults.hdr.tone_mapper = ToneMapperConfig{};
  for (const TrainOption& row : TrainOptionTable()) {
    if (!row.key.empty()) {
      EXPECT_TRUE(keys.insert(row.key).second) << row.key;
    }
    if (row.flag.empty()) continue;
    EXPECT_TRUE(flags.insert(row.flag).second) << row.flag;
    EXPECT_FALSE(row.help.empty()) << row.flag;
    EXPECT_EQ(row.flag.rfind("--", 0), 0u) << row.flag;
    if (row.type == OptionType::kBool) {
      EXPECT_TRUE(row.switch_value.is_boolean()) << row.flag;
    }
    // A default the help shows is one the option accepts.
    if (row.show_default) {
      EXPECT_EQ(row.Check(row.get(defaults)), "") << row.flag;
    }
  }
  // 36 + issue 55's thirteen + issue 52's four + issue 56's --exposure-unit
  EXPECT_EQ(flags.size(), 54u);
  EXPECT_EQ(FindTrainOption("--no-learn-background"), FindTrainOption("learn_background"));
}

TEST(TrainOptionsTable, AResumedRunMayChangeHowLongAndHowFastOnly) {
  std::set<std::string> may;
  for (const TrainOption& row : TrainOptionTable())
    if (row.may_change_on_resume) may.insert(row.key);
  EXPECT_EQ(may, (std::set<std::string>{"threads", "test_every", "checkpoint_every", "max_seconds",
                                        "optimization.iterations", "optimization.stop_window",
                                        "optimization.stop_tolerance", "optimization.stop_on_val"}));
  EXPECT_TRUE(MayChangeOnResume("optimization.iterations"));
  EXPECT_FALSE(MayChangeOnResume("iterations"));
  EXPECT_FALSE(MayChangeOnResume("seed"));
}

// --iterations auto keeps the run length (the schedules' and the cap) and turns the stop rule on
// with its stated window; a number is a number; any other word is refused.
TEST(TrainOptionsTable, IterationsAutoTurnsTheStopRuleOn) {
  const TrainOption* iterations = FindTrainOption("--iterations");
  ASSERT_NE(iterations, nullptr);
  EXPECT_EQ(iterations->Check("auto"), "");
  EXPECT_EQ(iterations->Check("Auto"), "expected an integer >= 1 or auto, got \"Auto\"");
  TrainOptions o;
  iterations->set(&o, "auto");
  EXPECT_EQ(o.optimization.iterations, 20000);
  EXPECT_EQ(o.optimization.stop_window, OptimizationOptions::kDefaultStopWindow);
  EXPECT_EQ(o.optimization.stop_tolerance, OptimizationOptions::kDefaultStopTolerance);
  o.optimization.stop_window = 250;  // a window given stays
  iterations->set(&o, "auto");
  EXPECT_EQ(o.optimization.stop_window, 250);
  iterations->set(&o, 3000);
  EXPECT_EQ(o.optimization.iterations, 3000);
  EXPECT_EQ(o.optimization.stop_window, 250);
  EXPECT_EQ(FindTrainOption("--stop-tolerance")->Check(1.5), "expected a number in [0, 1], got 1.5");
  EXPECT_EQ(FindTrainOption("--stop-window")->Check(-3, false), "expected an integer >= 0, got -3");
}

// --reference: the paper's configuration, recorded; an option that does less is refused with it.
TEST(TrainOptionsTable, ReferenceIsRecordedAndRefusesTheOptionsThatDoLess) {
  const TrainOption* reference = FindTrainOption("--reference");
  ASSERT_NE(reference, nullptr);
  TrainOptions o = Recordable();
  o.optimization.visible_adam = true;
  o.optimization.coarse_to_fine = 500;
  o.optimization.prune_contribution = 0.02;
  o.optimization.prune_radiance_share = true;
  o.optimization.clone_opacity_correction = true;
  reference->set_given(&o, true);
  EXPECT_FALSE(o.optimization.prune_radiance_share);
  EXPECT_TRUE(o.reference);
  EXPECT_FALSE(o.optimization.visible_adam);
  EXPECT_EQ(o.optimization.coarse_to_fine, 0);
  EXPECT_EQ(o.optimization.prune_contribution, 0.0);
  EXPECT_EQ(o.optimization.clone_opacity_correction, false);
  EXPECT_FALSE(o.optimization.color_bands_by_need);
  EXPECT_EQ(o.hdr.tone_mapper->unseen_rows, "zero");
  EXPECT_EQ(o.Validate(), "");
  EXPECT_EQ(o.ToJson()["reference"], true);
  EXPECT_TRUE(TrainOptions::FromJson(o.ToJson(), "/runs/a/config.json").reference);
  o.optimization.visible_adam = true;
  EXPECT_NE(o.Validate().find("drop --visible-adam"), std::string::npos) << o.Validate();
  o.optimization.visible_adam = false;
  o.optimization.clone_opacity_correction = true;
  EXPECT_NE(o.Validate().find("drop --clone-opacity-correction"), std::string::npos)
      << o.Validate();
  o.optimization.clone_opacity_correction = false;
  o.optimization.stop_window = 1000;
  EXPECT_NE(o.Validate().find("drop --iterations auto"), std::string::npos) << o.Validate();
  o.optimization.stop_window = 0;
  o.optimization.coarse_to_fine = 100;
  EXPECT_NE(o.Validate().find("drop --coarse-to-fine"), std::string::npos) << o.Validate();
  EXPECT_FALSE(MayChangeOnResume("optimization.coarse_to_fine"));
  o.optimization.coarse_to_fine = 0;
  o.optimization.prune_contribution = 0.02;
  EXPECT_NE(o.Validate().find("drop --prune-contribution"), std::string::npos) << o.Validate();
  EXPECT_FALSE(MayChangeOnResume("optimization.prune_contribution"));
  o.optimization.prune_contribution = 0;
  o.optimization.color_bands_by_need = true;
  EXPECT_NE(o.Validate().find("drop --color-bands-by-need"), std::string::npos) << o.Validate();
  EXPECT_FALSE(MayChangeOnResume("optimization.color_bands_by_need"));
  EXPECT_FALSE(MayChangeOnResume("optimization.color_band_signal"));
  // A resumed run cannot change what it learns: --visible-adam is not one a resume may change.
  EXPECT_FALSE(MayChangeOnResume("reference"));
  EXPECT_FALSE(MayChangeOnResume("optimization.visible_adam"));
}

}  // namespace
}  // namespace hdr4d::method
