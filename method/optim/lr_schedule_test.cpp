#include "method/optim/lr_schedule.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace hdr4d::method {
namespace {

// Relative comparison for learning rates spanning many decades.
void ExpectRelNear(double actual, double expected, double rel = 1e-12) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << "expected " << expected;
}

TEST(ExponentialLr, GoldenValuesOfThePositionSchedule) {
  const ExponentialLr lr{1.6e-4, 1.6e-6, 15000};
  ExpectRelNear(lr(0), 1.6e-4);
  ExpectRelNear(lr(15000), 1.6e-6);
  ExpectRelNear(lr(7500), 1.6e-5);                  // the geometric mean
  ExpectRelNear(lr(3750), 5.0596442562694074e-05);  // 1.6e-4 * 0.01^(1/4)
  ExpectRelNear(lr(30000), 1.6e-6);                 // held after max_steps
  EXPECT_EQ(lr(-1), 0.0);
  // Strictly decreasing in between.
  for (int s = 1; s <= 15000; s += 499) EXPECT_LT(lr(s), lr(s - 1)) << s;
}

TEST(ExponentialLr, DelayedWarmUp) {
  const ExponentialLr lr{1.0, 0.1, 100, 10, 0.01};
  ExpectRelNear(lr(0), 0.01);                 // delay_mult x init
  ExpectRelNear(lr(5), 0.6328199956536485);   // (0.01 + 0.99 sin(pi/4)) 0.1^0.05
  ExpectRelNear(lr(10), std::pow(0.1, 0.1));  // warm-up over
  ExpectRelNear(lr(100), 0.1);
  // delay_mult 1 (the default) means no warm-up even with delay steps.
  const ExponentialLr flat{1.0, 0.1, 100, 10, 1.0};
  ExpectRelNear(flat(5), std::pow(0.1, 0.05));
}

TEST(ExponentialLr, ZeroRatesAndConstantSchedules) {
  const ExponentialLr off{0.0, 0.0, 100};
  EXPECT_EQ(off.Validate(), "");
  for (int s : {-5, 0, 50, 100, 1000}) EXPECT_EQ(off(s), 0.0);
  const ExponentialLr same{2e-3, 2e-3, 100};
  for (int s : {0, 37, 100, 500}) ExpectRelNear(same(s), 2e-3);
  const ConstantLr constant{5e-4};
  for (int s : {-1, 0, 20000}) EXPECT_EQ(constant(s), 5e-4);
}

TEST(ExponentialLr, ValidateNamesTheProblem) {
  EXPECT_EQ((ExponentialLr{1.6e-4, 1.6e-6, 15000}.Validate()), "");
  EXPECT_NE((ExponentialLr{0.0, 1e-6, 10}.Validate()).find("initial learning rate"),
            std::string::npos);
  EXPECT_NE((ExponentialLr{1e-4, -1.0, 10}.Validate()).find("final learning rate"),
            std::string::npos);
  EXPECT_NE((ExponentialLr{1e-4, NAN, 10}.Validate()).find("final learning rate"),
            std::string::npos);
  EXPECT_NE((ExponentialLr{1e-4, 1e-6, 0}.Validate()).find("max_steps"), std::string::npos);
  EXPECT_NE((ExponentialLr{1e-4, 1e-6, 10, -1}.Validate()).find("delay_steps"), std::string::npos);
  EXPECT_NE((ExponentialLr{1e-4, 1e-6, 10, 5, -0.5}.Validate()).find("delay_mult"),
            std::string::npos);
}

TEST(OptimizationOptions, ReferenceDefaults) {
  // A 20000-iteration run on 400-pixel images is the reference's.
  const OptimizationOptions o = OptimizationOptions{}.Resolved(400.0);
  EXPECT_EQ(o.Validate(), "");
  EXPECT_EQ(o.iterations, 20000);
  EXPECT_EQ(o.batch_size, 1);
  EXPECT_EQ(o.position_lr_init, 1.6e-4);
  EXPECT_EQ(o.position_lr_final, 1.6e-6);
  EXPECT_EQ(o.position_lr_max_steps, 15000);
  EXPECT_EQ(o.position_lr_max_steps, o.densify_until);
  EXPECT_EQ(o.position_lr_delay_steps, 0);
  EXPECT_EQ(o.f_dc_lr, 2.5e-3);
  EXPECT_EQ(o.f_rest_lr, 1.25e-4);
  EXPECT_EQ(o.opacity_lr, 0.05);
  EXPECT_EQ(o.scaling_lr, 5e-3);
  EXPECT_EQ(o.rotation_lr, 1e-3);
  EXPECT_EQ(o.tone_mapper_lr, 5e-4);
  EXPECT_EQ(o.adam_eps, 1e-15);
  EXPECT_EQ(o.lambda_dssim, 0.2);
  EXPECT_EQ(o.densify_from, 500);
  EXPECT_EQ(o.densify_until, 15000);
  EXPECT_EQ(o.densification_interval, 200);
  EXPECT_EQ(o.densify_grad_threshold, 2e-4);
  EXPECT_EQ(o.percent_dense, 0.01);
  EXPECT_EQ(o.opacity_reset_interval, 3000);
  EXPECT_EQ(o.prune_opacity, 0.005);
  EXPECT_EQ(o.sh_increase_interval, 1000);
  EXPECT_EQ(o.clone_opacity_correction, false);
}

// The colour schedule and the clone correction are unset by default (so that a resumed run takes
// what it recorded); unset resolves to the reference's, and a set value stays.
TEST(OptimizationOptions, ColourScheduleFieldsResolveToTheReferenceUnlessSet) {
  OptimizationOptions o;
  EXPECT_LT(o.sh_increase_interval, 0);
  EXPECT_FALSE(o.clone_opacity_correction.has_value());
  EXPECT_EQ(o.Validate(), "");
  o.sh_increase_interval = 500;
  o.clone_opacity_correction = true;
  const OptimizationOptions r = o.Resolved(200.0);
  EXPECT_EQ(r.sh_increase_interval, 500);
  EXPECT_EQ(r.clone_opacity_correction, true);
  const OptimizationOptions unset = OptimizationOptions{}.Resolved(200.0);
  EXPECT_EQ(unset.sh_increase_interval, kReferenceShIncreaseInterval);
  EXPECT_EQ(unset.clone_opacity_correction, false);
}

TEST(OptimizationOptions, SchedulesFollowTheRunLengthUnlessSet) {
  OptimizationOptions o;
  o.iterations = 3000;
  const OptimizationOptions r = o.Resolved(100.0);
  EXPECT_EQ(r.Validate(), "");
  EXPECT_EQ(r.position_lr_max_steps, 2250);
  EXPECT_EQ(r.densify_from, 75);
  EXPECT_EQ(r.densify_until, 2250);
  EXPECT_EQ(r.densification_interval, 200);  // not scaled (see lr_schedule.h)
  EXPECT_EQ(r.opacity_reset_interval, 3000);  // the reference's: scaled resets ruin short runs
  EXPECT_EQ(r.sh_increase_interval, 1000);
  EXPECT_DOUBLE_EQ(r.densify_grad_threshold, 8e-4);  // 2e-4 x 400 / 100
  EXPECT_DOUBLE_EQ(o.Resolved(800.0).densify_grad_threshold, 1e-4);
  // Unresolved options still decay the position rate over the scaled window.
  EXPECT_EQ(o.PositionLr(1.0).max_steps, 2250);
  // Explicit values win; a short run never starts densifying after an explicit end.
  o.densify_until = 50;
  o.densify_grad_threshold = 1e-3;
  o.position_lr_max_steps = 3000;
  const OptimizationOptions e = o.Resolved(100.0);
  EXPECT_EQ(e.densify_until, 50);
  EXPECT_EQ(e.densify_from, 50);
  EXPECT_EQ(e.densify_grad_threshold, 1e-3);
  EXPECT_EQ(e.position_lr_max_steps, 3000);
  EXPECT_EQ(e.opacity_reset_interval, 3000);
  o.opacity_reset_interval = 450;  // an explicit interval wins
  EXPECT_EQ(o.Resolved(100.0).opacity_reset_interval, 450);
  // Tiny runs keep every step count at least 1; a bad image size falls back to 400 px.
  o = OptimizationOptions{};
  o.iterations = 10;
  const OptimizationOptions tiny = o.Resolved(0.0);
  EXPECT_EQ(tiny.opacity_reset_interval, 3000);
  EXPECT_EQ(tiny.position_lr_max_steps, 8);
  EXPECT_EQ(tiny.densify_from, 1);
  EXPECT_EQ(tiny.densify_grad_threshold, 2e-4);
  EXPECT_EQ(tiny.Validate(), "");
}

TEST(OptimizationOptions, PositionAndTimeRatesScaleWithExtent) {
  OptimizationOptions o;
  const ExponentialLr xyz = o.PositionLr(2.5);
  ExpectRelNear(xyz(0), 4e-4);
  ExpectRelNear(xyz(15000), 4e-6);
  ExpectRelNear(xyz(7500), 4e-5);
  EXPECT_EQ(xyz.Validate(), "");
  ExpectRelNear(o.TLr(2.5)(0), 4e-4);  // t defaults to position_lr_init, constant
  ExpectRelNear(o.TLr(2.5)(19999), 4e-4);
  o.t_lr_init = 1e-3;
  ExpectRelNear(o.TLr(2.5)(123), 2.5e-3);
}

TEST(OptimizationOptions, ValidateNamesTheBadField) {
  struct Case {
    std::string field;
    std::function<void(OptimizationOptions&)> spoil;
  };
  const std::vector<Case> cases = {
      {"iterations", [](auto& o) { o.iterations = 0; }},
      {"batch_size", [](auto& o) { o.batch_size = 0; }},
      {"position_lr_init", [](auto& o) { o.position_lr_init = 0.0; }},
      {"position_lr_final", [](auto& o) { o.position_lr_final = -1.6e-6; }},
      {"position_lr_max_steps", [](auto& o) { o.position_lr_max_steps = 0; }},
      {"densify_until", [](auto& o) {
         o.densify_from = 200;
         o.densify_until = 100;
       }},
      {"position_lr_delay_steps", [](auto& o) { o.position_lr_delay_steps = -1; }},
      {"position_lr_delay_mult", [](auto& o) { o.position_lr_delay_mult = NAN; }},
      {"t_lr_init", [](auto& o) { o.t_lr_init = INFINITY; }},
      {"f_dc_lr", [](auto& o) { o.f_dc_lr = -1.0; }},
      {"f_rest_lr", [](auto& o) { o.f_rest_lr = NAN; }},
      {"opacity_lr", [](auto& o) { o.opacity_lr = -0.05; }},
      {"scaling_lr", [](auto& o) { o.scaling_lr = INFINITY; }},
      {"rotation_lr", [](auto& o) { o.rotation_lr = -1e-3; }},
      {"tone_mapper_lr", [](auto& o) { o.tone_mapper_lr = NAN; }},
      {"adam_eps", [](auto& o) { o.adam_eps = 0.0; }},
      {"lambda_dssim", [](auto& o) { o.lambda_dssim = 1.5; }},
      {"densification_interval", [](auto& o) { o.densification_interval = 0; }},
      {"densify_grad_threshold", [](auto& o) { o.densify_grad_threshold = 0.0; }},
      {"densify_grad_threshold", [](auto& o) { o.densify_grad_threshold = INFINITY; }},
      {"percent_dense", [](auto& o) { o.percent_dense = 0.0; }},
      {"opacity_reset_interval", [](auto& o) { o.opacity_reset_interval = 0; }},
      {"prune_opacity", [](auto& o) { o.prune_opacity = 1.0; }},
      {"sh_increase_interval", [](auto& o) { o.sh_increase_interval = 0; }},
  };
  for (const Case& c : cases) {
    OptimizationOptions o;
    c.spoil(o);
    const std::string message = o.Validate();
    EXPECT_EQ(message.rfind(c.field, 0), 0u) << c.field << ": \"" << message << "\"";
  }
  // Zero learning rates freeze a group: allowed.
  OptimizationOptions frozen;
  frozen.f_rest_lr = 0.0;
  frozen.tone_mapper_lr = 0.0;
  EXPECT_EQ(frozen.Validate(), "");
}

// The default budget: 2 x the pixels of one view, at least 2 x 128 x 128.
TEST(GaussianBudget, TwiceOneViewsPixelsWithAFloor) {
  EXPECT_EQ(DefaultGaussianBudget(400.0 * 400.0), 320000);  // the paper's Syn resolution
  EXPECT_EQ(DefaultGaussianBudget(200.0 * 200.0), 80000);
  EXPECT_EQ(DefaultGaussianBudget(128.0 * 128.0), 32768);
  EXPECT_EQ(DefaultGaussianBudget(64.0 * 64.0), 32768);  // the floor
  EXPECT_EQ(DefaultGaussianBudget(0.0), 32768);
  EXPECT_EQ(DefaultGaussianBudget(-5.0), 32768);
}

// Beyond one 200 x 200 view the default of a dynamic scene follows the side: the same below.
TEST(GaussianBudget, BeyondTwoHundredPixelsTheSideNotTheArea) {
  EXPECT_EQ(SideScaledGaussianBudget(400.0 * 400.0), 160000);  // the paper's Syn resolution
  EXPECT_EQ(SideScaledGaussianBudget(800.0 * 800.0), 320000);
  EXPECT_EQ(SideScaledGaussianBudget(240.0 * 240.0), 96000);
  for (double side : {0.0, 64.0, 128.0, 150.0, 200.0})
    EXPECT_EQ(SideScaledGaussianBudget(side * side), DefaultGaussianBudget(side * side)) << side;
  EXPECT_EQ(SideScaledGaussianBudget(-5.0), 32768);
  // Continuous at 200 px and below the area's beyond it.
  EXPECT_NEAR(SideScaledGaussianBudget(200.0 * 200.0 + 1), 80000, 1);
  for (double side = 201; side < 2000; side *= 1.7)
    EXPECT_LT(SideScaledGaussianBudget(side * side), DefaultGaussianBudget(side * side)) << side;
}

// One moving camera: one view's pixels (by the side beyond 200 px), the same floor, never more
// than a rig's default.
TEST(GaussianBudget, MonocularIsOneViewsPixels) {
  EXPECT_EQ(MonocularGaussianBudget(200.0 * 200.0), 40000);
  EXPECT_EQ(MonocularGaussianBudget(400.0 * 400.0), 80000);
  EXPECT_EQ(MonocularGaussianBudget(100.0 * 100.0), 32768);  // D-NeRF at 100 px: as before
  EXPECT_EQ(MonocularGaussianBudget(-5.0), 32768);
  for (double side = 64; side < 2000; side *= 1.3)
    EXPECT_LE(MonocularGaussianBudget(side * side), SideScaledGaussianBudget(side * side)) << side;
}

// A static scene: one view's pixels per view of content, between the floor and 2 x every view's
// pixels (the old static rule, still --reference's).
TEST(GaussianBudget, StaticIsOneViewsPixelsPerViewOfContent) {
  const double view = 200.0 * 200.0, every = 20 * view;  // syn200_20k: a ring of 20 views
  EXPECT_EQ(StaticGaussianBudget(view, 1.0, every), 40000);
  EXPECT_EQ(StaticGaussianBudget(view, 1.04, every), 41600);
  EXPECT_EQ(StaticGaussianBudget(view, 5.0, every), 200000);  // a walk-around capture
  EXPECT_EQ(StaticGaussianBudget(view, 50.0, every), DefaultGaussianBudget(every));  // ceiling
  EXPECT_EQ(StaticGaussianBudget(128.0 * 128.0, 1.0, 8 * 128.0 * 128.0), 32768);     // floor
  EXPECT_EQ(StaticGaussianBudget(400.0 * 400.0, 1.0, 20 * 400.0 * 400.0), 80000);   // by side
  // Guarded: less than one view of content, NaN or infinity count as one view.
  for (double bad : {0.0, -3.0, 0.5, std::nan(""), HUGE_VAL})
    EXPECT_EQ(StaticGaussianBudget(view, bad, every), 40000) << bad;
  // Never above the old rule, even for a single small view.
  EXPECT_EQ(StaticGaussianBudget(view, 3.0, view), DefaultGaussianBudget(view));
}

}  // namespace
}  // namespace hdr4d::method
