// What the trainer optimises and supervises beyond plain 4DGS: the colour mode, the tone mapper
// and the supervision branches of HDR-4DGS (ARCHITECTURE §4). Generic switches only; the named
// methods of the paper's tables (hdr4dgs, 4dgs, 4dgs-hdr, hdr-gs) are presets of these, set by
// baselines/scene_baselines.h.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/metrics/metrics.h"
#include "method/gaussian/gaussian_model.h"
#include "method/render/resolved_hdr_training.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

enum class Supervision { kAuto, kLdr, kHdr, kLdrHdr };

// The HDR term's target (issue 12 §3, docs/history/accuracy.md "LDR+HDR supervision"):
//   image-max  the reference's mu(gt / max of that image), mu = 5000: a light that dims over
//              time changes every other pixel's target, and the dark half of the range is
//              almost flat under mu = 5000;
//   scene-log  gt / one maximum over all training views, encoded with mu = 1e6 (log-like over
//              six decades): one consistent scale for the whole scene, dark and bright alike;
//   aligned    the reference's target, compared after scaling each view's render by one factor
//              (the median ratio of target to render, a constant of the step): the term then
//              constrains the HDR's shape and leaves its scale, which changes from image to image
//              under per-image maxima, to the LDR terms and their known exposures.
enum class HdrTarget { kImageMax, kSceneLog, kAligned };

inline constexpr double kSceneLogMu = 1e6;
inline double HdrTargetMu(HdrTarget t) { return t == HdrTarget::kSceneLog ? kSceneLogMu : kMuLawMu; }
const char* HdrTargetName(HdrTarget t);
HdrTarget ParseHdrTarget(const std::string& name, const std::string& what);
// "auto", "ldr", "hdr", "ldr+hdr"; ParseSupervision throws hdr4d::Error naming `what`.
const char* SupervisionName(Supervision s);
Supervision ParseSupervision(const std::string& name, const std::string& what);

// The defaults are plain LDR 4DGS; `hdr4d train`'s default method, hdr4dgs, is a preset.
struct HdrTrainingOptions {
  std::string method = "4dgs";  // the preset's name, recorded in the run
  ColorMode color_mode = ColorMode::kLdr;
  bool force_static = false;  // no time axis even on a dynamic scene (HDR-GS on dynamic scenes)
  std::optional<ToneMapperConfig> tone_mapper;  // none: no tone mapping
  // auto: LDR, plus HDR where the training views have HDR ground truth (the reference's rule).
  Supervision supervision = Supervision::kAuto;
  bool pixel_branch = true;     // the 2D branch: the tone curves per pixel on the HDR raster
  bool gaussian_branch = true;  // the 3D branch: tone-mapped Gaussians in the raster (6 ch)
  float hdr_weight = 0.6f;      // alpha of the HDR term
  HdrTarget hdr_target = HdrTarget::kImageMax;
  // Whether the HDR term's gradient reaches the geometry (means, covariances, opacities, hence
  // the densification statistics) or, false (--no-hdr-geometry), the colours only, the geometry
  // then following the LDR terms alone (issue 12 §3, docs/history/accuracy.md). Needs an LDR term.
  bool hdr_geometry = true;
  // --hdr-head: LDR+HDR supervision as an HDR head (method/train/hdr_head_fit.h, issue 12
  // §3): the run trains on the LDR terms exactly as LDR alone (no HDR term in the loop), then
  // fits a per-Gaussian log-radiance offset that only the HDR output uses to the HDR ground
  // truth, everything else frozen. The LDR output is LDR alone's, bit for bit.
  bool hdr_head = false;
  int hdr_head_iterations = 0;  // 0: half of the run's iterations
  // The floor of the 2D branch's log(HDR + eps); unset: ResolveHdrTraining picks
  // kHdrUnitsPixelLogEpsilon with an HDR term, else kReferencePixelLogEpsilon (both in
  // method/render/pixel_log.h, with why).
  std::optional<float> pixel_log_epsilon;

  std::string Validate() const;
  nlohmann::json ToJson() const;
  static HdrTrainingOptions FromJson(const nlohmann::json& json, const std::string& source);
};

// The switches resolved against a scene and a tone mapper (ResolvedHdrTraining,
// method/render/resolved_hdr_training.h: what one training view computes). Throws hdr4d::Error
// when the combination cannot train on this scene (HDR supervision without HDR ground truth, a
// whole-image mapper without the pixel branch, ...). pointwise: whether the tone mapper (if any)
// maps values on their own.
ResolvedHdrTraining ResolveHdrTraining(const HdrTrainingOptions& options,
                                       bool train_views_have_hdr,
                                       bool pointwise);

}  // namespace hdr4d::method
