// The Dynamic Tone Mapper of HDR-4DGS (paper §3.3; ARCHITECTURE §4): a radiance bank of mean log-HDR
// colours per timestamp, a context learner (GRU by default) over the window of rows before the
// view's time giving the context f, and per-channel tone curves g_c(log HDR + log e, f). Works
// per Gaussian (3D branch) and per pixel (2D branch) with the same weights and context.
//
// Order per view, as the reference renders: ObserveMeanLogHdr(time, mean) with this render's
// mean log-HDR colour first (at time index 0 the window is that very row), then BeginFrame.
// A BeginFrame while a view's gradient is still pending (MapBackward without EndFrameBackward)
// first flushes it into grads().
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "method/tonemap/dtm_core.h"
#include "method/tonemap/radiance_bank.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

class DynamicToneMapper final : public ToneMapper {
 public:
  // kind "dtm"; throws hdr4d::Error for an invalid configuration or another kind. The
  // parameters are initialised from config.seed, the bank to zeros.
  explicit DynamicToneMapper(const ToneMapperConfig& config);

  const ToneMapperConfig& config() const override { return config_; }
  bool pointwise() const override { return true; }

  // Throws hdr4d::Error for a time index outside the bank or a non-finite log exposure.
  void BeginFrame(const ToneFrame& frame) override;
  void Map(const float* log_hdr, std::size_t n, float* ldr) const override;
  void MapBackward(const float* log_hdr,
                   std::size_t n,
                   const float* dL_dldr,
                   float* dL_dlog_hdr) override;
  void EndFrameBackward() override;
  // Throws hdr4d::Error for a time index outside the bank; a non-finite mean is ignored.
  void ObserveMeanLogHdr(int time_index, const float* mean_log_hdr) override;

  std::vector<float>& params() override { return params_; }
  std::vector<float>& grads() override { return grads_; }

  // "HDR4DDTM" | u32 version | u32 n, n bytes of the configuration as JSON | u64 count, f32
  // params | u32 rows, f32 bank (rows x 3) | u64 FNV-1a of everything after the version. Load
  // requires the same structure (kind, context learner, window, sizes, timestamps); the speed
  // options (tabulated, table_nodes) and the seed may differ. It writes params() in place (an
  // optimiser may hold its address).
  void Save(std::ostream& out) const override;
  void Load(std::istream& in, const std::string& source) override;

  const RadianceBank& bank() const { return bank_; }
  // The context f of the current view (empty before the first BeginFrame).
  const std::vector<float>& context() const { return core_.context(); }
  const DtmShape& shape() const { return core_.shape(); }

 private:
  void CheckTimeIndex(int time_index, const char* what) const;

  ToneMapperConfig config_;
  DtmCore<float> core_;
  RadianceBank bank_;
  std::vector<float> params_, grads_, window_;
};

}  // namespace hdr4d::method
