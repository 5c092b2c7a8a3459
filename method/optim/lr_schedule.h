// Learning-rate schedules and the optimisation options of 4DGS / HDR-4DGS (ARCHITECTURE §4
// "Optimisation"). Header-only.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>

namespace hdr4d::method {

// The reference's get_expon_lr_func: a log-linear interpolation from `init` at step 0 to `final`
// at step max_steps (held there afterwards),
//   lr(step) = exp((1 - p) ln(init) + p ln(final)),   p = clamp(step / max_steps, 0, 1),
// optionally times a warm-up factor when delay_steps > 0:
//   delay_mult + (1 - delay_mult) sin(pi/2 clamp(step / delay_steps, 0, 1)).
// lr = 0 for step < 0 and when init == final == 0. The midpoint is the geometric mean.
struct ExponentialLr {
  double init = 0.0;
  double final = 0.0;
  int max_steps = 1;
  int delay_steps = 0;
  double delay_mult = 1.0;

  double operator()(int step) const {
    if (step < 0 || (init == 0.0 && final == 0.0)) return 0.0;
    double delay = 1.0;
    if (delay_steps > 0) {
      const double q = std::clamp(static_cast<double>(step) / delay_steps, 0.0, 1.0);
      delay = delay_mult + (1.0 - delay_mult) * std::sin(0.5 * std::numbers::pi * q);
    }
    const double p = std::clamp(static_cast<double>(step) / max_steps, 0.0, 1.0);
    return delay * std::exp((1.0 - p) * std::log(init) + p * std::log(final));
  }

  // "" when usable, else the problem: init and final both positive (or both 0, "off"), finite;
  // max_steps > 0; delay_steps >= 0; delay_mult finite and >= 0.
  std::string Validate() const {
    const bool off = init == 0.0 && final == 0.0;
    if (!off && !(init > 0.0 && std::isfinite(init))) {
      return fmt::format("initial learning rate must be positive and finite, got {}", init);
    }
    if (!off && !(final > 0.0 && std::isfinite(final))) {
      return fmt::format("final learning rate must be positive and finite, got {}", final);
    }
    if (max_steps <= 0) return fmt::format("max_steps must be positive, got {}", max_steps);
    if (delay_steps < 0) return fmt::format("delay_steps must be >= 0, got {}", delay_steps);
    if (!(delay_mult >= 0.0) || !std::isfinite(delay_mult)) {
      return fmt::format("delay_mult must be finite and >= 0, got {}", delay_mult);
    }
    return "";
  }
};

// The same learning rate at every step (the reference's t, colour, opacity, scale, rotation and
// tone-mapper groups).
struct ConstantLr {
  double lr = 0.0;
  double operator()(int /*step*/) const { return lr; }
};

// The reference's schedules are those of its 20000-iteration runs (every HDR-4DGS config), and
// its densification threshold that of its 400-pixel training images (HDR-4D-Syn and D-NeRF at
// resolution 2).
inline constexpr int kReferenceIterations = 20000;
inline constexpr double kReferenceImageSize = 400.0;
// A schedule field set to this (any negative value) follows the run length; see Resolved().
inline constexpr int kFollowRunLength = -1;
// The fewest initial points a run starts from: a point cloud with fewer is replaced by random
// points (each point's scale is its distance to three neighbours).
inline constexpr int kMinInitialPoints = 4;

// The reference's `reference_steps` of a 20000-iteration run scaled to `iterations`, at least 1.
inline int StepsForRunLength(int reference_steps, int iterations) {
  const double scaled = double(reference_steps) * double(iterations) / kReferenceIterations;
  return std::max(1, static_cast<int>(std::lround(scaled)));
}

// The default Gaussian budget: kGaussiansPerPixel x `pixels`, at least kMinGaussianBudget. For a
// dynamic scene `pixels` is one training view's (the median view at the training resolution),
// not all the cameras of a rig at one time: a rig's cameras see the same surfaces, and the count
// a run reaches follows one view's pixels whatever the number of cameras (33-49k at 200 px with
// 1 to 10 cameras, 3000 iterations). For a static scene it is every view's pixels (its views are
// its one time). Small images need more Gaussians per pixel (a 64 px rig reaches 4.4 per pixel
// of one view), hence the floor, 2 x 128 x 128. It is a ceiling against runaway growth in long
// runs: capped there, a four-camera rig was better on held-out views than growing freely and an
// eight-camera one 0.36 dB worse; 2 x keeps the paper's Syn configuration (four 400 px cameras)
// under 2 GB (docs/history/gaussian-budget.md).
inline constexpr double kGaussiansPerPixel = 2.0;
inline constexpr std::int64_t kMinGaussianBudget = 32768;
inline std::int64_t DefaultGaussianBudget(double pixels, double per_pixel = kGaussiansPerPixel) {
  return std::max<std::int64_t>(kMinGaussianBudget,
                                std::llround(per_pixel * std::max(0.0, pixels)));
}

// The default of a dynamic scene (issue 55; --reference keeps the one above): up to one
// 200 x 200 view as above, and beyond it the budget follows the view's side, not its area
// (2 x sqrt(pixels x 200^2): 160k at 400 px, 320k at 800 px). What needs more Gaussians at a
// higher resolution is detail along edges and silhouettes, which grows with the side; flat
// surfaces do not need more. Measured on the paper's Syn configuration (four 400 px cameras,
// docs/history/time-to-quality.md): 160k ended 0.23 dB better held out than the 320k of
// 2 x the area, in 0.66 of the time. Every scene of 200 px or less keeps its budget.
inline constexpr double kSideScaledAbovePixels = 200.0 * 200.0;
inline double SideScaledPixels(double pixels) {
  const double p = std::max(0.0, pixels);
  return p > kSideScaledAbovePixels ? std::sqrt(p * kSideScaledAbovePixels) : p;
}
inline std::int64_t SideScaledGaussianBudget(double pixels) {
  return DefaultGaussianBudget(SideScaledPixels(pixels));
}

// The default of a monocular dynamic scene (one training view per instant: a moving camera;
// issue 55, not under --reference): half of the above, one view's pixels (by its side beyond
// 200 px), at least kMinGaussianBudget. One view per instant constrains each Gaussian from one
// direction at a time, so a model grown to 2 x the pixels fits each training frame with
// Gaussians no other view checks, and long runs lose on held-out views: the datagen minis at
// 20000 iterations (docs/history/time-to-quality.md, "One moving camera: half the budget").
// At 200 px this is 40k; D-NeRF-sized scenes (100 px) keep the floor as before.
inline constexpr double kMonocularGaussiansPerPixel = 1.0;
inline std::int64_t MonocularGaussianBudget(double pixels) {
  return DefaultGaussianBudget(SideScaledPixels(pixels), kMonocularGaussiansPerPixel);
}

// The default of a static scene (issue 55; --reference keeps 2 x every view's pixels, the first
// rule above): one view's pixels (by its side beyond 200 px) for each view's worth of distinct
// content the cameras hold (`content_views`, train/content_views.h: about 1 for a ring round an
// object, more for a walk-around capture whose views see different parts), at least
// kMinGaussianBudget and at most 2 x every view's pixels. A static Gaussian is seen at every
// instant, and a dynamic rig at its budget shows 0.9-1.4 x one view's pixels at one instant
// (38-55k of 80k on five datagen rig minis at 200 px, 20000 iterations; ring5 at 128 px 0.9), so
// one view's pixels per view of content is the low end of what one instant of a rig holds.
// Growing freely, a 20-view ring (200 px) reaches 69k and overfits its held-out view
// (docs/history/time-to-quality.md, "A static scene's budget"). Non-finite or < 1 content
// counts as 1.
inline constexpr double kStaticGaussiansPerViewPixel = 1.0;
inline std::int64_t StaticGaussianBudget(double view_pixels, double content_views,
                                         double every_view_pixels) {
  const double views = std::isfinite(content_views) ? std::max(1.0, content_views) : 1.0;
  const std::int64_t ceiling = DefaultGaussianBudget(every_view_pixels);
  return std::min(ceiling, DefaultGaussianBudget(SideScaledPixels(view_pixels) * views,
                                                 kStaticGaussiansPerViewPixel));
}

// The reference's colour schedule: one more SH band (and, with a time axis, time band) every
// 1000 iterations. A band every 500 with the clone opacity correction
// (`--sh-increase-interval 500 --clone-opacity-correction`) reaches a static ring's held-out
// PSNR much sooner, but ends 0.4-1.0 dB lower on three of four seeds of a real capture at 20000
// iterations, so it is not a default anywhere (docs/history/time-to-quality.md, "The many-view
// schedule on scenes it was not set on").
inline constexpr int kReferenceShIncreaseInterval = 1000;

// Checks of OptimizationOptions::Validate: "" when the value is usable, else the message.
namespace option_checks {
inline std::string PositiveInt(const char* name, int v) {
  return v > 0 ? std::string() : fmt::format("{} must be positive, got {}", name, v);
}
inline std::string Rate(const char* name, double v) {
  return v >= 0.0 && std::isfinite(v) ? std::string()
                                      : fmt::format("{} must be finite and >= 0, got {}", name, v);
}
inline std::string Positive(const char* name, double v) {
  return v > 0.0 && std::isfinite(v)
             ? std::string()
             : fmt::format("{} must be positive and finite, got {}", name, v);
}
// A negative schedule field follows the run length (Resolved); 0 is not a schedule.
inline std::string Schedule(const char* name, int v) {
  return v != 0 ? std::string()
                : fmt::format("{} must be positive (or negative: follow the run length), got 0",
                              name);
}
}  // namespace option_checks

// Optimisation settings with the HDR-4DGS HDR-4D-Syn defaults (which are the 4DGS ones except for
// iterations, the densification interval and the tone mapper). Learning rates of the 4D mean
// (xyz and t) are in scene-extent units: the caller multiplies them by the extent (PositionLr,
// TLr). Iterations are counted from 1 as in the reference training loop.
//
// Schedules follow the run length: the fields marked "scaled" default to kFollowRunLength and
// Resolved() gives them the reference's value times iterations / 20000 (so a 20000-iteration
// run is the reference's, and a 3000-iteration run densifies until 2250, decays the position
// learning rate over 2250 steps, ...), and the densification threshold the reference's 2e-4
// times 400 / the image size (the mean screen-space gradient of a Gaussian a few pixels wide
// grows as the image shrinks, so 2e-4 over-densifies small images). A value set explicitly is
// used as it is. The densification interval and the colour-degree interval stay the
// reference's: scaled down they densify and unlock SH detail too often for the views a step
// sees (a 3000-iteration run on the known Gaussian scene: 28.5 dB scaled, 31.8 dB not;
// docs/history/accuracy.md, issue 12 §1).
struct OptimizationOptions {
  int iterations = 20000;
  int batch_size = 1;  // camera/time samples per step; losses are divided by it

  // xyz: decays log-linearly from init to final x extent over position_lr_max_steps (the
  // reference sets it equal to densify_until). The reference passes delay_mult 0.01 but delay
  // steps 0, so there is no warm-up by default.
  double position_lr_init = 1.6e-4;
  double position_lr_final = 1.6e-6;
  int position_lr_max_steps = kFollowRunLength;  // scaled: 15000 of 20000
  int position_lr_delay_steps = 0;
  double position_lr_delay_mult = 0.01;
  // t: constant (the reference's t scheduler is commented out); < 0 means position_lr_init.
  double t_lr_init = -1.0;
  double f_dc_lr = 2.5e-3;
  // The colours' DC when they are log-HDR (Resolved(.., true) uses it for f_dc_lr): 16x the
  // reference's. Log colours span about ten units (ln of a 1e4:1 scene) where LDR colours span
  // one, and at 2.5e-3 they cannot spread that far in a run: the tone curve squeezes the HDR
  // instead (slope 0.27 of the truth's; 0.79 at 0.04; docs/history/accuracy.md).
  double f_dc_lr_log_hdr = 4e-2;
  double f_rest_lr = 2.5e-3 / 20.0;
  double opacity_lr = 0.05;
  double scaling_lr = 5e-3;   // the xyz and the t log-scales
  double rotation_lr = 1e-3;  // both quaternions
  double tone_mapper_lr = 5e-4;
  double adam_eps = 1e-15;

  double lambda_dssim = 0.2;

  // Densification: every densification_interval iterations in (densify_from, densify_until),
  // clone / split where the mean screen-space gradient norm >= densify_grad_threshold; clone when
  // the largest scale <= percent_dense x extent. Opacity reset every opacity_reset_interval;
  // prune opacity < prune_opacity. One more SH degree every sh_increase_interval.
  int densify_from = kFollowRunLength;            // scaled: 500 of 20000
  int densify_until = kFollowRunLength;           // scaled: 15000 of 20000
  int densification_interval = 200;
  double densify_grad_threshold = kFollowRunLength;  // scaled: 2e-4 at 400 px, x 400 / size
  double percent_dense = 0.01;
  // Resolved to the reference's 3000 whatever the run length: scaled resets (every 450 of 3000
  // iterations) leave the model no time to recover between them (docs/history/accuracy.md).
  int opacity_reset_interval = kFollowRunLength;
  double prune_opacity = 0.005;
  // Negative: the reference's 1000 (Resolved()); kept unset in a run's request so that a resumed
  // run takes the value its config.json recorded (runs of 2026-12-06 recorded 500 on some
  // static scenes).
  int sh_increase_interval = kFollowRunLength;
  // Gaussian budget (the reference's densify_until_num_points): densification never takes the
  // count past it. 0 = none; kFollowRunLength (any negative value) = the default budget from
  // the training images, set by the trainer (DefaultGaussianBudget).
  std::int64_t max_gaussians = kFollowRunLength;

  // ---- Doing less where a scene does not need it (issue 55; `--reference` turns all off) ----
  // Visible-set Adam: a Gaussian's rows are stepped only in the iterations that gave them a
  // gradient; when it is seen again its moments' decay over the k steps it missed is caught up
  // exactly (m *= beta1^k, v *= beta2^k). Not dense Adam: the parameter's drift during those
  // steps (dense Adam keeps moving it along its momentum) is skipped (adam.h, "Visible rows").
  bool visible_adam = false;
  // --iterations auto: stop once the mean training loss over the last stop_window iterations
  // has improved by less than stop_tolerance (relative) on the window before, both windows
  // after densification ended (the model no longer grows). 0 = run all iterations.
  int stop_window = 0;
  double stop_tolerance = kDefaultStopTolerance;
  // --stop-on-val: the same stop decided on the scene's val split instead of the training loss:
  // its views are scored every stop_window iterations (also while densifying: before that
  // iteration's densification and opacity reset) and the run stops, on the model it scored, once
  // kHeldOutPatience evaluations in a row have not improved on the best
  // (method/train/loss_plateau.h). Catches a model that overfits its
  // training views, which the training loss cannot see.
  bool stop_on_val = false;
  // --grow-on-val: with --stop-on-val, the same val evaluations also decide how far the model
  // grows: from the first one, while densifying, that did not improve on the best, the count
  // stays at or under the count then (method/train/loss_plateau.h, FindGrowthStop). Off: the
  // budget alone (max_gaussians) caps it.
  bool grow_on_val = false;
  // --keep-best-val: with --stop-on-val, the run ends on the model of its best val evaluation
  // (written to RUN/best_val.bin when one improves on the best, taken back at the stop) instead
  // of the last. Off: better held out on some scenes with val splits and worse on others, two
  // seeds each (docs/history/time-to-quality.md, "Keeping the best val model").
  bool keep_best_val = false;
  // Coarse-to-fine images: the first coarse_to_fine iterations render and supervise at 1/4 of
  // the images' size (first half) and 1/2 (second half), the columns and rows a factor leaves
  // over sitting out (method/train/coarse_images.h). 0 = full size throughout.
  int coarse_to_fine = 0;
  // Pruning by contribution: at a densification step, a Gaussian seen since the last one whose
  // largest blending weight alpha T at any pixel of those views stayed below this is pruned
  // (DensifyParams::min_contribution). 0 = off.
  double prune_contribution = 0.0;
  // With prune_contribution: the statistic is a Gaussian's largest share of a pixel, its weight
  // raised to its part of the pixel's HDR radiance where that is larger (blend.h ShareScale).
  bool prune_radiance_share = false;
  // Colour bands by need (method/train/color_bands.h): where the reference adds a colour band,
  // a probe of its gradient switches it on only when the gradients of the views agree (their
  // summed square over the sum of squares reaches color_band_signal, about 1 for noise); false:
  // every band on the reference's schedule. Off by default: on five datagen scenes it kept held-out
  // LDR but lost aligned HDR (docs/history/time-to-quality.md).
  bool color_bands_by_need = false;
  double color_band_signal = kDefaultColorBandSignal;
  // --clone-opacity-correction: a clone and its source both get opacity 1 - sqrt(1 - alpha), so
  // the two copies (same place, same shape) blend as the one did before (Rota Bulo et al.,
  // "Revising Densification in Gaussian Splatting", ECCV 2024); false: both keep alpha, as the
  // paper's densification. Unset: false (Resolved()), or on resume what the run recorded.
  std::optional<bool> clone_opacity_correction;
  static constexpr double kDefaultColorBandSignal = 2.0;
  static constexpr int kDefaultStopWindow = 1000;
  static constexpr double kDefaultStopTolerance = 0.002;

  // The reference's values of the resolved fields (a 20000-iteration run on 400-pixel images).
  static constexpr int kRefPositionLrMaxSteps = 15000;
  static constexpr int kRefDensifyFrom = 500;
  static constexpr int kRefDensifyUntil = 15000;
  static constexpr double kRefDensifyGradThreshold = 2e-4;
  static constexpr int kRefOpacityResetInterval = 3000;

  // A copy with every field that follows the run length given its value for `iterations` and
  // training images of `image_size` pixels (the geometric mean of width and height, > 0). The
  // densification window and the position-LR decay scale with the run; the opacity reset keeps
  // the reference's interval (a short run then resets rarely or never).
  OptimizationOptions Resolved(double image_size, bool log_hdr_colors = false) const {
    OptimizationOptions r = *this;
    if (log_hdr_colors) r.f_dc_lr = f_dc_lr_log_hdr;
    auto steps = [&](int& field, int reference) {
      if (field < 0) field = StepsForRunLength(reference, iterations);
    };
    steps(r.position_lr_max_steps, kRefPositionLrMaxSteps);
    steps(r.densify_until, kRefDensifyUntil);
    if (r.opacity_reset_interval < 0) r.opacity_reset_interval = kRefOpacityResetInterval;
    if (r.sh_increase_interval < 0) r.sh_increase_interval = kReferenceShIncreaseInterval;
    if (!r.clone_opacity_correction) r.clone_opacity_correction = false;
    if (r.densify_from < 0) {
      // Never past an explicit densify_until (a short run that densifies early).
      r.densify_from = std::min(StepsForRunLength(kRefDensifyFrom, iterations), r.densify_until);
    }
    if (r.densify_grad_threshold < 0) {
      const double size = image_size > 0 && std::isfinite(image_size) ? image_size
                                                                       : kReferenceImageSize;
      r.densify_grad_threshold = kRefDensifyGradThreshold * kReferenceImageSize / size;
    }
    return r;
  }

  // The xyz schedule for a scene of the given extent.
  ExponentialLr PositionLr(double extent) const {
    const int steps = position_lr_max_steps > 0
                          ? position_lr_max_steps
                          : StepsForRunLength(kRefPositionLrMaxSteps, iterations);
    return ExponentialLr{position_lr_init * extent, position_lr_final * extent, steps,
                         position_lr_delay_steps, position_lr_delay_mult};
  }
  // The t learning rate for a scene of the given extent.
  ConstantLr TLr(double extent) const {
    return ConstantLr{(t_lr_init < 0.0 ? position_lr_init : t_lr_init) * extent};
  }

  // "" when every field is usable, else a message that starts with the bad field's name.
  std::string Validate() const {
    if (std::string e = ValidateRunAndRates(); !e.empty()) return e;
    return ValidateDensifyAndStop();
  }
  // The run length, the batch and every learning rate.
  std::string ValidateRunAndRates() const {
    using namespace option_checks;
    std::string e;
    if (!(e = PositiveInt("iterations", iterations)).empty()) return e;
    if (!(e = PositiveInt("batch_size", batch_size)).empty()) return e;
    if (!(e = Positive("position_lr_init", position_lr_init)).empty()) return e;
    if (!(e = Positive("position_lr_final", position_lr_final)).empty()) return e;
    if (!(e = Schedule("position_lr_max_steps", position_lr_max_steps)).empty()) return e;
    if (position_lr_delay_steps < 0) {
      return fmt::format("position_lr_delay_steps must be >= 0, got {}", position_lr_delay_steps);
    }
    if (!(e = Rate("position_lr_delay_mult", position_lr_delay_mult)).empty()) return e;
    if (!std::isfinite(t_lr_init)) {
      return fmt::format("t_lr_init must be finite (< 0 means position_lr_init), got {}",
                         t_lr_init);
    }
    if (!(e = Rate("f_dc_lr", f_dc_lr)).empty()) return e;
    if (!(e = Rate("f_dc_lr_log_hdr", f_dc_lr_log_hdr)).empty()) return e;
    if (!(e = Rate("f_rest_lr", f_rest_lr)).empty()) return e;
    if (!(e = Rate("opacity_lr", opacity_lr)).empty()) return e;
    if (!(e = Rate("scaling_lr", scaling_lr)).empty()) return e;
    if (!(e = Rate("rotation_lr", rotation_lr)).empty()) return e;
    if (!(e = Rate("tone_mapper_lr", tone_mapper_lr)).empty()) return e;
    if (!(e = Positive("adam_eps", adam_eps)).empty()) return e;
    if (!(lambda_dssim >= 0.0 && lambda_dssim <= 1.0)) {
      return fmt::format("lambda_dssim must be in [0, 1], got {}", lambda_dssim);
    }
    return "";
  }
  // Densification, pruning, the colour schedule and the stop.
  std::string ValidateDensifyAndStop() const {
    using namespace option_checks;
    std::string e;
    if (densify_from >= 0 && densify_until >= 0 && densify_until < densify_from) {
      return fmt::format("densify_until ({}) must be >= densify_from ({})", densify_until,
                         densify_from);
    }
    if (!(e = PositiveInt("densification_interval", densification_interval)).empty()) return e;
    if (densify_grad_threshold == 0.0 || !std::isfinite(densify_grad_threshold)) {
      return fmt::format(
          "densify_grad_threshold must be positive and finite (or negative: scaled to the image "
          "size), got {}",
          densify_grad_threshold);
    }
    // A run starts from at least kMinInitialPoints (a smaller cloud falls back to random
    // points), so a smaller budget could not be kept.
    if (max_gaussians > 0 && max_gaussians < kMinInitialPoints) {
      return fmt::format("max_gaussians: --max-gaussians must be 0 (no budget) or at least {} "
                         "(the fewest points a run starts from), got {}",
                         kMinInitialPoints, max_gaussians);
    }
    if (!(percent_dense > 0.0 && percent_dense <= 1.0)) {
      return fmt::format("percent_dense must be in (0, 1], got {}", percent_dense);
    }
    if (prune_radiance_share && !(prune_contribution > 0.0)) {
      return "prune_radiance_share: --prune-radiance-share changes what --prune-contribution "
             "measures; give --prune-contribution T (T > 0) as well";
    }
    if (!(e = Schedule("opacity_reset_interval", opacity_reset_interval)).empty()) return e;
    if (!(prune_opacity >= 0.0 && prune_opacity < 1.0)) {
      return fmt::format("prune_opacity must be in [0, 1), got {}", prune_opacity);
    }
    if (sh_increase_interval == 0)
      return "sh_increase_interval must be positive (or negative: by the scene's views), got 0";
    if (!(color_band_signal >= 0.0 && std::isfinite(color_band_signal)))
      return fmt::format("color_band_signal must be >= 0 and finite, got {}", color_band_signal);
    if (stop_window < 0) return fmt::format("stop_window must be >= 0, got {}", stop_window);
    if (!(stop_tolerance >= 0.0 && stop_tolerance <= 1.0)) {
      return fmt::format("stop_tolerance must be in [0, 1], got {}", stop_tolerance);
    }
    if (stop_on_val && stop_window == 0)
      return "stop_on_val: --stop-on-val decides when --iterations auto stops; add --iterations "
             "auto (or --stop-window N)";
    return "";
  }
};

}  // namespace hdr4d::method
