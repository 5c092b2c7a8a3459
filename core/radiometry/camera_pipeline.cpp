#include "core/radiometry/camera_pipeline.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/radiometry/camera_pipeline_auto_exposure.h"
#include "core/radiometry/camera_pipeline_phone.h"
#include "core/radiometry/camera_pipeline_rig_mismatch.h"
#include "core/radiometry/camera_pipeline_vignetting.h"
#include "core/util/error.h"

namespace hdr4d {
namespace {

void CheckRange(const char* flag, double value, double min, double max) {
  if (!std::isfinite(value) || value < min || value > max)
    Fail("camera pipeline: {} must be within [{}, {}], got {}", flag, min, max, value);
}

}  // namespace

const std::vector<std::string>& CameraPipelineNames() {
  static const std::vector<std::string> names = {"fixed", "auto-exposure", "phone",
                                                 "rig-mismatch"};
  return names;
}

void CameraPipelineOptions::Validate() const {
  const auto& names = CameraPipelineNames();
  if (std::find(names.begin(), names.end(), name) == names.end())
    Fail("camera pipeline: unknown pipeline '{}' (use {})", name, fmt::join(names, ", "));
  if (ae_scope != "rig" && ae_scope != "camera")
    Fail("camera pipeline: --ae-scope must be rig or camera, got '{}'", ae_scope);
  CheckRange("--ae-lag", ae_lag, 0, 10);
  CheckRange("--ae-strength", ae_strength, 0, 1);
  CheckRange("the tone curve's low percentile", tone_low_percentile, 0, 100);
  CheckRange("the tone curve's high percentile", tone_high_percentile, 0, 100);
  if (!(tone_low_percentile < tone_high_percentile))
    Fail("camera pipeline: the tone curve's low percentile {} must be below the high one {}",
         tone_low_percentile, tone_high_percentile);
  CheckRange("--wb-drift", wb_drift, 0, 2);
  CheckRange("--wb-period", wb_period, 1e-6, 1e6);
  CheckRange("--mismatch-gain", mismatch_gain, 0, 3);
  CheckRange("--mismatch-response", mismatch_response, 0, 0.5);
  CheckRange("--mismatch-colour", mismatch_colour, 0, 0.3);
  CheckRange("--vignetting", vignetting, 0, 0.99);
}

nlohmann::json CameraPipelineOptions::ToJson() const {
  nlohmann::json j = {{"name", name}};
  if (name == "auto-exposure" || name == "phone") {
    j["auto_exposure"] = {{"scope", ae_scope}, {"lag", ae_lag}, {"strength", ae_strength}};
  }
  if (name == "phone") {
    j["tone_curve"] = {{"model", "filmic(x / white), fitted per view"},
                       {"low_percentile", tone_low_percentile},
                       {"high_percentile", tone_high_percentile},
                       {"toe", kPhoneToe}};
    j["white_balance_drift"] = {{"amplitude", wb_drift}, {"period", wb_period}};
  }
  if (name == "rig-mismatch") {
    j["rig_mismatch"] = {{"gain", mismatch_gain},
                         {"response", mismatch_response},
                         {"colour", mismatch_colour},
                         {"seed", seed}};
  }
  j["vignetting"] = vignetting;
  return j;
}

nlohmann::json ViewProcessing::ToJson() const {
  nlohmann::json j = {{"gain", gain}, {"white_balance", white_balance}, {"colour", colour}};
  if (response) j["response"] = response->ToJson();
  if (!curve.is_null()) j["curve"] = curve;
  return j;
}

std::vector<ViewProcessing> PlanViews(const CameraPipelineOptions& options,
                                      const std::vector<PipelineView>& views,
                                      const std::shared_ptr<const Crf>& base,
                                      double reference_exposure) {
  options.Validate();
  std::vector<ViewProcessing> out(views.size());
  if (options.name == "auto-exposure" || options.name == "phone") {
    const std::vector<double> gains =
        AutoExposureGains(views, options.ae_scope, options.ae_lag, options.ae_strength);
    for (std::size_t i = 0; i < views.size(); ++i) out[i].gain = gains[i];
  }
  if (options.name == "phone") {
    for (std::size_t i = 0; i < views.size(); ++i) {
      const PhoneCurve curve = FitPhoneCurve(views[i].stats, reference_exposure * out[i].gain);
      out[i].curve = curve.ToJson();
      out[i].response = std::make_shared<BentCrf>(
          std::make_shared<FilmicCrf>(curve.contrast, curve.mid), 1.0, curve.white);
      out[i].white_balance =
          WhiteBalanceDrift(views[i].camera, views[i].time, options.wb_drift, options.wb_period);
    }
  }
  if (options.name == "rig-mismatch" && !views.empty()) {
    int reference = views[0].camera;
    for (const PipelineView& v : views) reference = std::min(reference, v.camera);
    for (std::size_t i = 0; i < views.size(); ++i) {
      const RigCameraDifference d =
          DrawRigCamera(options.seed, views[i].camera, views[i].camera == reference,
                        options.mismatch_gain, options.mismatch_response, options.mismatch_colour);
      out[i].gain = d.gain;
      out[i].colour = d.colour;
      out[i].response = std::make_shared<BentCrf>(base, d.exponent, 1.0);
    }
  }
  return out;
}

Image SynthesizeView(const Image& hdr, const ViewProcessing& view,
                     const CameraPipelineOptions& options, const Crf& base,
                     const LdrSynthesisOptions& ldr) {
  if (options.IsIdentity()) return SynthesizeLdr(hdr, base, ldr);
  if (hdr.encoding() != Encoding::kLinear)
    Fail("camera pipeline: expected linear HDR radiance, got a display-encoded image ({})",
         hdr.ShapeString());
  for (float v : hdr.values()) {
    // SynthesizeLdr names the pixel; mixing channels first could hide a negative value.
    if (!std::isfinite(v) || v < 0)
      return SynthesizeLdr(hdr, base, ldr);  // throws with the pixel's position
  }
  Image scaled = hdr.Rgb();
  ApplyVignetting(scaled, options.vignetting);
  std::array<double, 9> m;  // gain * W * M
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      m[r * 3 + c] = view.gain * view.white_balance[r] * view.colour[r * 3 + c];
  float* v = scaled.data();
  for (std::size_t p = 0; p < scaled.num_pixels(); ++p) {
    float* px = v + p * 3;
    const double in[3] = {px[0], px[1], px[2]};
    for (int r = 0; r < 3; ++r) {
      // A colour matrix with negative off-diagonals can push a saturated colour below zero,
      // where no sensor goes.
      const double y = m[r * 3] * in[0] + m[r * 3 + 1] * in[1] + m[r * 3 + 2] * in[2];
      px[r] = static_cast<float>(std::min(std::max(y, 0.0), 3.0e38));
    }
  }
  return SynthesizeLdr(scaled, view.response ? *view.response : base, ldr);
}

BentCrf::BentCrf(std::shared_ptr<const Crf> base, double exponent, double white)
    : base_(std::move(base)), exponent_(exponent), white_(white) {
  if (!base_) Fail("bent response: no base response");
  if (!std::isfinite(exponent) || !(exponent > 0))
    Fail("bent response: exponent {} must be finite and > 0", exponent);
  if (!std::isfinite(white) || !(white > 0))
    Fail("bent response: white point {} must be finite and > 0", white);
}

double BentCrf::Apply(double x) const {
  return base_->Apply(std::pow(std::max(x, 0.0) / white_, exponent_));
}

double BentCrf::Saturation() const {
  return white_ * std::pow(base_->Saturation(), 1.0 / exponent_);
}

double BentCrf::Inverse(double y) const {
  return white_ * std::pow(base_->Inverse(y), 1.0 / exponent_);
}

std::string BentCrf::Spec() const {
  return fmt::format("{} of (x / {:.6g})^{:.6g}", base_->Spec(), white_, exponent_);
}

nlohmann::json BentCrf::ToJson() const {
  return {{"model", "bent"}, {"exponent", exponent_}, {"white", white_},
          {"base", base_->ToJson()}};
}

}  // namespace hdr4d
