// A learned per-camera exposure and white-balance correction (`hdr4d train --camera-correction`;
// not in the paper): each training camera k gets three log gains d_k (one per channel), added
// to the tone curve's input, so that camera's LDR is
//   LDR = TM(log c + log e_t + d_k)
// on both branches (per Gaussian and per pixel): a camera whose pipeline applies its own gain or
// channel gains before its response (a rig of unlike cameras, an auto-exposure per camera) is
// explained by its d_k instead of by the scene's colours or the shared curve. The HDR output
// (exp of the log colours) is the scene's and takes no correction.
//
// Regularised towards identity: the loss gains weight * |d_k|^2 for each camera whose views
// the step rendered, so d_k moves only as far as the images ask (and a shift shared by every
// camera, which the shared curve could take as well, stays small).
//
// Evaluation: a view of a training camera (a held-out time of a rig camera) uses its d_k; a
// view of any other camera (a held-out camera, a novel view, the video) uses d = 0, the
// identity: there is nothing to learn its gain from.
//
// It wraps the run's tone mapper: every call goes to the mapper with the input shifted by the
// view's d (ToneFrame::camera_index selects it); the mapper's parameters, state and checkpoint
// section are the inner mapper's, unchanged. Its own values are stepped by their own Adam,
// lazily: only the rows of cameras whose views the step rendered, each with its own step count
// (a camera seen one step in ten is not pulled by stale moments in between).
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

// The key of a checkpoint's trainer state that holds the correction (ToJson).
inline constexpr const char* kCameraCorrectionKey = "camera_correction";

struct CameraCorrectionOptions {
  double weight = 0.01;  // of weight * |d_k|^2 per camera stepped
  double lr = 0.002;     // Adam's learning rate on d
};

class CameraCorrectedToneMapper final : public ToneMapper {
 public:
  // cameras: the number of training cameras (rows), >= 1.
  CameraCorrectedToneMapper(std::unique_ptr<ToneMapper> inner, int cameras,
                            CameraCorrectionOptions options);

  const ToneMapperConfig& config() const override { return inner_->config(); }
  bool pointwise() const override { return inner_->pointwise(); }
  void BeginFrame(const ToneFrame& frame) override;
  void Map(const float* log_hdr, std::size_t n, float* ldr) const override;
  void MapBackward(const float* log_hdr, std::size_t n, const float* dL_dldr,
                   float* dL_dlog_hdr) override;
  void MapImage(const float* log_hdr, int width, int height, float* ldr) const override;
  void MapImageBackward(const float* log_hdr, int width, int height, const float* dL_dldr,
                        float* dL_dlog_hdr) override;
  void EndFrameBackward() override { inner_->EndFrameBackward(); }
  void ObserveMeanLogHdr(int time_index, const float* mean_log_hdr) override {
    inner_->ObserveMeanLogHdr(time_index, mean_log_hdr);  // the scene's radiance, uncorrected
  }
  std::vector<float>& params() override { return inner_->params(); }
  std::vector<float>& grads() override { return inner_->grads(); }
  float learning_rate() const override { return inner_->learning_rate(); }
  void Save(std::ostream& out) const override { inner_->Save(out); }
  void Load(std::istream& in, const std::string& source) override { inner_->Load(in, source); }

  ToneMapper& inner() { return *inner_; }
  int cameras() const { return static_cast<int>(log_gain_.size() / 3); }
  // d, cameras x 3, and dL/dd (added to by the backward calls).
  std::vector<float>& log_gains() { return log_gain_; }
  const std::vector<float>& log_gains() const { return log_gain_; }
  const std::vector<float>& log_gain_grads() const { return grad_; }
  // The shift of the current frame (zero for camera_index -1).
  const float* current_shift() const { return shift_; }

  // Before a step's views: no gradient, no camera seen.
  void ZeroGrad();
  // Multiplies the gradient gathered so far (a batch's mean).
  void ScaleGrad(float factor);
  // The regulariser's value over the cameras seen since ZeroGrad (for reporting), and one Adam
  // step of those rows with it added. Throws hdr4d::Error when a gradient is not finite.
  double Regulariser() const;
  void Step();

  // Values, Adam moments and step counts, for a checkpoint's trainer state; FromJson throws
  // hdr4d::Error naming `source` when the record is missing, of another camera count, or holds
  // a value that is not finite.
  nlohmann::json ToJson() const;
  void FromJson(const nlohmann::json& trainer, const std::string& source);

 private:
  // The frame's shift added to n RGB values into scratch (returned).
  const float* Shifted(const float* log_hdr, std::size_t n, std::vector<float>* scratch) const;
  void AddGrad(const float* dL_dx, std::size_t n);

  std::unique_ptr<ToneMapper> inner_;
  CameraCorrectionOptions options_;
  std::vector<float> log_gain_, grad_, m_, v_;
  std::vector<std::int64_t> steps_;  // per camera
  std::vector<std::uint8_t> seen_;   // per camera, since ZeroGrad
  int row_ = -1;
  float shift_[3] = {0, 0, 0};
  std::vector<float> backward_scratch_, input_scratch_;
};

}  // namespace hdr4d::method
