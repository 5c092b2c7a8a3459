// Camera pipelines: documented models of what a camera does between the scene's radiance and
// the stored LDR image beyond one fixed response. The dataset JSON keeps only the nominal
// exposure; what the pipeline did to each image (its gain, tone curve, white balance, colour
// matrix) is hidden from training and recorded in the scene's synthesis.json.
//
//   fixed          the dataset's response (filmic by default), nothing else: today's images.
//   auto-exposure  a gain that follows the frame's brightness with a lag, as a phone's AE:
//                  an exponential moving average over time of the log mean luminance
//                  (camera_pipeline_auto_exposure.h), rig-wide (one gain per timestamp for
//                  every camera) or per camera.
//   phone          auto-exposure, then a global tone curve fitted to each frame's histogram
//                  (shoulder and toe follow its log-luminance percentiles) and a white-balance
//                  drift over time (camera_pipeline_phone.h).
//   rig-mismatch   cameras with their own gain, response exponent and colour matrix; camera 0
//                  (the smallest id) is the reference (camera_pipeline_rig_mismatch.h).
// Optional with any of them: vignetting (camera_pipeline_vignetting.h).
//
// Per image, in this order (one "view" = one HDR image: a camera at a time; its brackets share
// the view's processing and differ only in exposure):
//   radiance -> x vignetting v(r) -> colour matrix M (camera's sensor) -> white balance W
//   -> x gain g -> then SynthesizeLdr: x exposure, sensor noise, response, clip, quantise.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/radiometry/crf.h"
#include "core/radiometry/frame_statistics.h"
#include "core/radiometry/ldr_synthesis.h"

namespace hdr4d {

struct CameraPipelineOptions {
  std::string name = "fixed";  // CameraPipelineNames()
  // auto-exposure, and phone's exposure:
  std::string ae_scope = "rig";  // "rig" (one gain per timestamp) or "camera"
  double ae_lag = 0.1;           // EMA time constant in normalised time [0,1]; 0 = no lag
  double ae_strength = 1.0;      // fraction of a brightness change the gain undoes, [0, 1]
  // phone:
  double tone_low_percentile = 1;    // of log luminance: sets the toe
  double tone_high_percentile = 99;  // sets the shoulder (white point)
  double wb_drift = 0.1;             // amplitude of ln(R gain) = -ln(B gain)
  double wb_period = 1.0;            // of the drift, in normalised time
  // rig-mismatch (each camera but the reference draws uniformly within these):
  double mismatch_gain = 0.3;      // ln gain in [-G, G]
  double mismatch_response = 0.1;  // response bent to crf(x^e), e in [1-E, 1+E]
  double mismatch_colour = 0.05;   // colour matrix: off-diagonals and ln channel gains in [-C, C]
  // any pipeline:
  double vignetting = 0;  // v(r) = 1 - s r^2, r = distance from the centre / half-diagonal
  std::uint64_t seed = 0;  // rig-mismatch's draws (the dataset synthesis passes its noise seed)

  // Throws hdr4d::Error naming the parameter for an unknown name or scope, or a value out of
  // range.
  void Validate() const;
  // fixed without vignetting: the images are exactly SynthesizeLdr's, nothing is recorded.
  bool IsIdentity() const { return name == "fixed" && vignetting == 0; }
  bool NeedsStatistics() const { return name == "auto-exposure" || name == "phone"; }
  nlohmann::json ToJson() const;  // the name and the parameters that model uses
};

const std::vector<std::string>& CameraPipelineNames();  // fixed, auto-exposure, phone, rig-mismatch

// One HDR image the pipeline sees: a camera at a time.
struct PipelineView {
  int camera = 0;
  double time = 0;  // normalised to [0,1]
  FrameStatistics stats;  // needed by auto-exposure and phone only
};

// What the pipeline does to one view, the hidden truth recorded per view.
struct ViewProcessing {
  double gain = 1;
  std::array<double, 3> white_balance = {1, 1, 1};
  std::array<double, 9> colour = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major, camera's sensor
  std::shared_ptr<const Crf> response;  // null: the dataset's response
  nlohmann::json curve;                 // the phone curve's parameters, null otherwise
  nlohmann::json ToJson() const;
};

// The processing of every view. reference_exposure: the exposure (s) the phone fits its curve
// at (the dataset synthesis passes the geometric mean of its frames' exposures).
std::vector<ViewProcessing> PlanViews(const CameraPipelineOptions& options,
                                      const std::vector<PipelineView>& views,
                                      const std::shared_ptr<const Crf>& base,
                                      double reference_exposure);

// One LDR image of a view. hdr: linear RGB radiance. With options.IsIdentity() this is
// SynthesizeLdr(hdr, base, ldr) byte for byte.
Image SynthesizeView(const Image& hdr, const ViewProcessing& view,
                     const CameraPipelineOptions& options, const Crf& base,
                     const LdrSynthesisOptions& ldr);

// A response bent in its input: y = base((x / white)^exponent). Saturates at
// white * base.Saturation()^(1/exponent). Its Spec() describes it for the record; ParseCrf
// cannot read it back (ToJson holds every parameter).
class BentCrf final : public Crf {
 public:
  BentCrf(std::shared_ptr<const Crf> base, double exponent, double white);
  double Apply(double x) const override;
  double Saturation() const override;
  bool Invertible() const override { return base_->Invertible(); }
  double Inverse(double y) const override;
  std::string Spec() const override;
  nlohmann::json ToJson() const override;

 private:
  std::shared_ptr<const Crf> base_;
  double exponent_, white_;
};

}  // namespace hdr4d
