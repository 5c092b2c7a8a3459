// What the baseline tone mappers share: the configuration, the current frame, one flat parameter
// array with its gradient, and the checkpoint format. Their only state is the parameters (no
// radiance bank), so Save/Load store exactly those.
//
// Format (little-endian):
//   "HDR4DTMB" | u32 version (1) | u32 kind length | kind bytes | u64 count | f32 params[count]
//   | u64 FNV-1a (64-bit) of every byte after the version field.
// Load checks everything (magic, version, kind, count, checksum, finite values) before it
// copies the values into the existing array, so a failed load changes nothing and a successful
// one keeps params().data() where an optimiser may have bound it.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "method/tonemap/tone_mapper.h"

namespace hdr4d::baselines {

class ParamToneMapper : public method::ToneMapper {
 public:
  const method::ToneMapperConfig& config() const override { return config_; }
  // Keeps the frame for the Map calls that follow. Its log exposure must be finite and its image
  // index >= -1 (checked: the trainer's invariant). Mappers with per-image parameters check more.
  void BeginFrame(const method::ToneFrame& frame) override;
  std::vector<float>& params() override { return params_; }
  std::vector<float>& grads() override { return grads_; }
  const method::ToneFrame& frame() const { return frame_; }

  void Save(std::ostream& out) const override;
  void Load(std::istream& in, const std::string& source) override;

 protected:
  ParamToneMapper(const method::ToneMapperConfig& config, std::vector<float> initial_params);

  method::ToneMapperConfig config_;
  method::ToneFrame frame_;
  std::vector<float> params_;
  std::vector<float> grads_;
};

}  // namespace hdr4d::baselines
