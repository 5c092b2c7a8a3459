#include "method/train/hdr_training_options.h"

#include "core/util/error.h"
#include "method/train/train_options_table.h"

namespace hdr4d::method {

const char* SupervisionName(Supervision s) {
  switch (s) {
    case Supervision::kAuto:
      return "auto";
    case Supervision::kLdr:
      return "ldr";
    case Supervision::kHdr:
      return "hdr";
    case Supervision::kLdrHdr:
      return "ldr+hdr";
  }
  return "?";
}

Supervision ParseSupervision(const std::string& name, const std::string& what) {
  for (Supervision s :
       {Supervision::kAuto, Supervision::kLdr, Supervision::kHdr, Supervision::kLdrHdr}) {
    if (name == SupervisionName(s)) return s;
  }
  Fail("{}: unknown supervision '{}' (auto, ldr, hdr or ldr+hdr)", what, name);
}

const char* HdrTargetName(HdrTarget t) {
  switch (t) {
    case HdrTarget::kImageMax:
      return "image-max";
    case HdrTarget::kSceneLog:
      return "scene-log";
    case HdrTarget::kAligned:
      return "aligned";
  }
  return "?";
}

HdrTarget ParseHdrTarget(const std::string& name, const std::string& what) {
  for (HdrTarget t : {HdrTarget::kImageMax, HdrTarget::kSceneLog, HdrTarget::kAligned}) {
    if (name == HdrTargetName(t)) return t;
  }
  Fail("{}: unknown HDR target '{}' (image-max, scene-log or aligned)", what, name);
}

std::string HdrTrainingOptions::Validate() const {
  // The ranges of hdr_weight, pixel_log_epsilon, ... as the option table states them.
  TrainOptions options;
  options.hdr = *this;
  if (std::string p = CheckTrainOptionValues(options, "hdr"); !p.empty()) return p;
  if (color_mode == ColorMode::kLdr) {
    if (hdr_head) return "an LDR colour model has no HDR output for an HDR head";
    if (tone_mapper) return "an LDR colour model has no tone mapper";
    if (supervision == Supervision::kHdr || supervision == Supervision::kLdrHdr)
      return "an LDR colour model cannot be supervised with HDR";
  }
  if (tone_mapper) {
    if (std::string p = tone_mapper->Validate(); !p.empty()) return "tone mapper: " + p;
    // Neither branch would tone-map anything: nothing would compare with the LDR images.
    if (!pixel_branch && !gaussian_branch)
      return "no tone-mapping branch left (drop --no-pixel-branch or --no-gaussian-branch)";
  }
  return "";
}

// RUN/config.json's "hdr": the rows of the option table under it (train_options_table.h).
nlohmann::json HdrTrainingOptions::ToJson() const {
  TrainOptions options;
  options.hdr = *this;
  return RecordTrainOptions(options, "hdr");
}

HdrTrainingOptions HdrTrainingOptions::FromJson(const nlohmann::json& j,
                                                const std::string& source) {
  TrainOptions options;
  ReadTrainOptionsRecord(j, source, "hdr", &options);
  return options.hdr;
}

ResolvedHdrTraining ResolveHdrTraining(const HdrTrainingOptions& o,
                                       bool train_views_have_hdr,
                                       bool pointwise) {
  if (std::string p = o.Validate(); !p.empty()) Fail("train: {}", p);
  ResolvedHdrTraining r;
  if (o.color_mode == ColorMode::kLdr) {
    r.hdr_colors = false;
    return r;  // plain 4DGS: the raster is the LDR image, one L1 + D-SSIM term
  }
  Supervision s = o.supervision;
  if (s == Supervision::kAuto) {
    if (o.tone_mapper) {
      s = train_views_have_hdr ? Supervision::kLdrHdr : Supervision::kLdr;
    } else {
      s = Supervision::kHdr;  // no tone mapper: nothing can be compared with the LDR images
    }
  }
  const bool ldr = s == Supervision::kLdr || s == Supervision::kLdrHdr;
  r.hdr = s == Supervision::kHdr || s == Supervision::kLdrHdr;
  if (o.hdr_head) {
    // The loop is LDR alone's; the HDR ground truth goes to the head after it.
    if (s != Supervision::kLdrHdr) {
      Fail(
          "train: --hdr-head fits the HDR output to HDR ground truth after training on the LDR "
          "images, so it needs supervision ldr+hdr (this run resolves to '{}'{})",
          SupervisionName(s), train_views_have_hdr ? "" : ": the scene has no HDR ground truth");
    }
    r.hdr = false;
    r.hdr_head = true;
  }
  r.pixel_log_epsilon = o.pixel_log_epsilon.value_or(r.hdr ? kHdrUnitsPixelLogEpsilon
                                                           : kReferencePixelLogEpsilon);
  if (r.hdr_head && !train_views_have_hdr) {
    Fail("train: --hdr-head fits the HDR output to HDR ground truth (exr_file_path), which this "
         "scene's training views do not have");
  }
  if (r.hdr && !train_views_have_hdr) {
    Fail(
        "train: supervision '{}' needs HDR ground truth (exr_file_path) in the training views; "
        "this scene has none (use --supervision ldr)",
        SupervisionName(s));
  }
  if (r.hdr && !ldr && !o.hdr_geometry) {
    Fail(
        "train: --no-hdr-geometry keeps the HDR term off the geometry, which then needs an LDR "
        "term; supervision '{}' has none (use --supervision ldr+hdr)",
        SupervisionName(s));
  }
  if (ldr && !o.tone_mapper) {
    Fail("train: LDR supervision of HDR colours needs a tone mapper (method '{}' has none)",
         o.method);
  }
  if (o.tone_mapper) {
    r.ldr_gaussian = ldr && o.gaussian_branch && pointwise;
    r.ldr_pixel = ldr && (o.pixel_branch || !pointwise);
    r.final_ldr_from_pixels = !pointwise || !o.gaussian_branch;
    if (!pointwise && !o.pixel_branch) {
      Fail(
          "train: the '{}' tone mapper works on whole images only, so it needs the pixel "
          "branch (drop --no-pixel-branch)",
          o.tone_mapper->kind);
    }
    if (r.hdr_head && r.final_ldr_from_pixels) {
      Fail(
          "train: --hdr-head keeps the LDR output apart from the HDR one, which needs the LDR "
          "from the tone-mapped Gaussians (the '{}' mapper{} makes it from the HDR pixels)",
          o.tone_mapper->kind, o.gaussian_branch ? "" : " with --no-gaussian-branch");
    }
  }
  return r;
}

}  // namespace hdr4d::method
