// The tone-mapper interface (ARCHITECTURE §4): a learned or fixed map from log-HDR colour, given the
// frame's log exposure and time index, to LDR colour in [0,1], with a backward to its inputs and
// to its own parameters. The same object serves both supervision branches of HDR-4DGS: per
// Gaussian (3D branch, before rasterisation) and per pixel (2D branch, after it).
//
// Every tone mapper of the paper's Table 4 implements it: the Dynamic Tone Mapper
// (method/tonemap/dynamic_tone_mapper.h) and the baselines (baselines/): static MLP (HDR-GS),
// sigmoid (HDR-HexPlane), Reinhard, Durand. They are built by kind through
// method/tonemap/tone_mapper_registry.h, where baselines/ registers its kinds.
//
// Frame protocol, for one rendered view:
//   BeginFrame(frame)                   once, before any mapping of that view;
//   Map / MapImage                      any number of times (const, thread-safe);
//   MapBackward / MapImageBackward      for each forward whose output has a loss;
//   EndFrameBackward()                  once, after the last backward of the view.
// Parameter gradients are ADDED to grads(); the trainer zeroes them before each iteration.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hdr4d::method {

// What a tone mapper knows of the view it maps.
struct ToneFrame {
  int time_index = 0;        // radiance-bank row of the view's timestamp, 0 .. num_times - 1
  int image_index = -1;      // training image (for per-image parameters); -1 for any other view
  float log_exposure = 0.f;  // natural log of the exposure time in seconds
  // The view's row of a per-camera correction (camera_correction.h): the training camera that
  // took it; -1 for a camera no training image came from (a held-out camera, a novel view).
  int camera_index = -1;
};

// Everything that selects and sizes a tone mapper; saved in RUN/config.json.
struct ToneMapperConfig {
  std::string kind = "dtm";  // dtm | mlp | sigmoid | reinhard | durand
  int num_times = 1;         // distinct normalised timestamps of the scene (radiance-bank rows)
  int num_images = 0;        // training images (per-image exposure of the sigmoid mapper)
  // Dynamic Tone Mapper (paper §3.3, Tables 6-7).
  std::string context_learner = "gru";  // gru | rnn | lstm | transformer
  int context_window = 20;              // k: bank rows the context learner reads
  int context_size = 2;                 // d: size of the context vector f_t
  int curve_hidden = 64;                // width of the two hidden layers of each tone curve
  // Speed option: map through a per-frame table of each channel's curve (exact gradients
  // through its nodes) instead of evaluating the MLP per value.
  bool tabulated = true;
  int table_nodes = 1024;
  // Learned curves (dtm, mlp) non-decreasing in log exposure by construction
  // (method/tonemap/monotone_mlp.h). false, the default, is the reference's free MLP: with log
  // colours at their own learning rate (lr_schedule.h, f_dc_lr_log_hdr) it learns a smooth
  // rising curve, and the monotone one adds nothing measurable (docs/history/accuracy.md). A
  // config.json without the key means false.
  bool monotone_curves = false;
  // How the context learner reads a radiance-bank row no training view wrote (radiance_bank.h):
  // "interpolate" (the default) between the nearest written rows in time, or "zero" as the
  // bank holds it (before issue 52's fix; --reference). A config.json without the key means
  // "zero".
  std::string unseen_rows = "interpolate";
  std::uint64_t seed = 0;  // initial weights

  // "" when valid, else a message naming the bad field.
  std::string Validate() const;
  nlohmann::json ToJson() const;
  // Throws hdr4d::Error naming `source` and the key when a value is missing or invalid.
  static ToneMapperConfig FromJson(const nlohmann::json& json, const std::string& source);
};

class ToneMapper {
 public:
  virtual ~ToneMapper() = default;

  virtual const ToneMapperConfig& config() const = 0;
  // True when each colour is mapped on its own, so the mapper can run per Gaussian (3D branch).
  // False for local operators (Durand) that need the whole image: only MapImage* then.
  virtual bool pointwise() const = 0;

  // Prepares what every value of the view shares (DTM: the context from the radiance bank).
  virtual void BeginFrame(const ToneFrame& frame) = 0;

  // Pointwise mapping of n RGB colours (interleaved n x 3): log_hdr is the natural log of the
  // radiance, without the exposure (the mapper adds the frame's log exposure itself). Requires
  // pointwise().
  virtual void Map(const float* log_hdr, std::size_t n, float* ldr) const = 0;
  // dL_dldr (n x 3) -> dL_dlog_hdr (n x 3, overwritten; may be null when not needed); adds the
  // parameter gradient to grads(). Deterministic at any thread count.
  virtual void MapBackward(const float* log_hdr,
                           std::size_t n,
                           const float* dL_dldr,
                           float* dL_dlog_hdr) = 0;

  // A whole H x W x 3 log-HDR image (2D branch). Pointwise mappers default to Map.
  virtual void MapImage(const float* log_hdr, int width, int height, float* ldr) const {
    Map(log_hdr, static_cast<std::size_t>(width) * height, ldr);
  }
  virtual void MapImageBackward(const float* log_hdr,
                                int width,
                                int height,
                                const float* dL_dldr,
                                float* dL_dlog_hdr) {
    MapBackward(log_hdr, static_cast<std::size_t>(width) * height, dL_dldr, dL_dlog_hdr);
  }

  // Back-propagates what this view's backward calls gathered into shared quantities (DTM:
  // dL/dcontext through the context learner) into grads().
  virtual void EndFrameBackward() {}

  // The radiance bank's input: the mean log-HDR colour (3 values) over all Gaussians at a render
  // of the view with this time index. Mappers without a bank ignore it.
  virtual void ObserveMeanLogHdr(int time_index, const float* mean_log_hdr) {}

  // All learnable parameters in one flat array and their gradients (same size): one Adam group.
  // Fixed mappers with no learnable parameter return empty arrays.
  virtual std::vector<float>& params() = 0;
  virtual std::vector<float>& grads() = 0;
  void ZeroGrad() { grads().assign(grads().size(), 0.f); }
  virtual float learning_rate() const { return 5e-4f; }  // ARCHITECTURE §4: tone mapper 5e-4

  // Checkpoint state: parameters and any state (the radiance bank), versioned. Load throws
  // hdr4d::Error naming `source` and the problem and leaves the mapper unchanged.
  virtual void Save(std::ostream& out) const = 0;
  virtual void Load(std::istream& in, const std::string& source) = 0;
};

}  // namespace hdr4d::method
