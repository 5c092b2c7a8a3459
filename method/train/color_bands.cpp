#include "method/train/color_bands.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d::method {

BandDegrees ScheduledDegrees(int iteration, const ColorBasis& basis, bool temporal, int interval) {
  const int steps = iteration / interval;
  const int sh = std::min(basis.max_sh_degree, steps);
  const int time =
      temporal ? std::clamp(steps - basis.max_sh_degree, 0, basis.max_time_degree) : 0;
  return {sh, time};
}

std::optional<BandDegrees> NextBand(BandDegrees d, const ColorBasis& basis, bool temporal) {
  if (d.sh < basis.max_sh_degree) return BandDegrees{d.sh + 1, d.time};
  if (temporal && d.time < basis.max_time_degree) return BandDegrees{d.sh, d.time + 1};
  return std::nullopt;
}

std::size_t RestColumns(BandDegrees d, const ColorBasis& basis, int channels) {
  return static_cast<std::size_t>(basis.used_coefficients(d.sh, d.time) - 1) *
         static_cast<std::size_t>(channels);
}

nlohmann::json BandDecision::ToJson() const {
  return {{"iteration", iteration}, {"sh_degree", band.sh},      {"time_degree", band.time},
          {"signal", signal},       {"dc_signal", dc_signal}, {"switched_on", switched_on}};
}

BandDecision BandDecision::FromJson(const nlohmann::json& j) {
  BandDecision d;
  d.iteration = j.at("iteration").get<int>();
  d.band = {j.at("sh_degree").get<int>(), j.at("time_degree").get<int>()};
  d.signal = j.at("signal").get<double>();
  d.dc_signal = j.at("dc_signal").get<double>();
  d.switched_on = j.at("switched_on").get<bool>();
  return d;
}

ColorBandGate::ColorBandGate(const ColorBasis& basis, bool temporal, int channels,
                             Options options)
    : basis_(basis), temporal_(temporal), channels_(channels), options_(options) {
  HDR4D_CHECK(options_.interval > 0 && options_.probe_iterations > 0 && channels_ > 0);
}

std::size_t ColorBandGate::band_columns() const {
  if (!candidate_) return 0;
  return RestColumns(*candidate_, basis_, channels_) - RestColumns(accepted_, basis_, channels_);
}

void ColorBandGate::Begin(int it, std::size_t num_gaussians) {
  if (probing() || it <= 1 || (it - 1) % options_.interval != 0) return;
  candidate_ = NextBand(accepted_, basis_, temporal_);
  if (!candidate_) return;
  probe_from_ = it;
  sums_.assign(num_gaussians * row_floats(), 0.0f);
}

// Per Gaussian, per band column j (channel c) and per channel: S_j = sum g_j, P_j = sum g_j g_dc,
// Q_j = sum g_j^2, then S_dc = sum g_dc and Q_dc = sum g_dc^2, and n, the views that saw it
// (layout in row_floats()).
void ColorBandGate::Add(std::int64_t b, std::int64_t e, const GradientRows& rows) {
  if (!probing()) return;
  const std::size_t first = RestColumns(accepted_, basis_, channels_);
  const std::size_t width = band_columns();
  const std::size_t stride = static_cast<std::size_t>(basis_.coefficients() - 1) * channels_;
  const std::size_t floats = row_floats();
  const std::size_t channels = static_cast<std::size_t>(channels_);
  for (std::int64_t g = b; g < e; ++g) {
    const std::size_t r = static_cast<std::size_t>(g - b);
    const float* band = rows.color_rest + r * stride + first;
    const float* dc = rows.color_dc + r * channels;
    // A Gaussian this view did not see (most of a dynamic scene's, culled by time) has zero rows
    // and adds nothing: skipped without touching its sums.
    if (std::all_of(dc, dc + channels, [](float v) { return v == 0.0f; })) continue;
    float* s = &sums_[static_cast<std::size_t>(g) * floats];
    for (std::size_t j = 0; j < width; ++j) {
      const float dcj = dc[j % channels];  // column j is channel j % channels
      s[j] += band[j];
      s[width + j] += band[j] * dcj;
      s[2 * width + j] += band[j] * band[j];
    }
    for (std::size_t c = 0; c < channels; ++c) {
      s[3 * width + c] += dc[c];
      s[3 * width + channels + c] += dc[c] * dc[c];
    }
    s[3 * width + 2 * channels] += 1.0f;
  }
}

// A band's gradient g_j = Y_j r and the DC's g_dc = C0 r share the residual r: where the DC term
// is still short of its value (r has a mean), the band's sum picks that up through the mean of
// Y_j over the views, whether or not the colour depends on the view. So each band column's series
// is first fitted by the DC's, g_j ~ beta g_dc (least squares through 0, beta = P / Q_dc); the
// rest is e = (Y_j - the r^2-weighted mean of Y_j) r, with
//   sum e = S_j - beta S_dc,  sum e^2 = Q_j - P^2 / Q_dc.
// Where e is noise of variance s^2 (Y_j unrelated to r), the fit leaves E[sum e^2] = (n - 1) s^2
// and E[(sum e)^2] = s^2 (n - S_dc^2 / Q_dc): the second is what the band's (sum e)^2 is
// measured against, so that noise reads 1 whatever the DC's mean. A Gaussian seen by fewer than 3
// views of the probe says nothing and is left out. Summed in double, in row order (the same on
// every thread count).
BandDecision ColorBandGate::Decide(int it) const {
  const std::size_t width = band_columns();
  const std::size_t floats = row_floats();
  const std::size_t channels = static_cast<std::size_t>(channels_);
  double band_sum2 = 0, band_null = 0, dc_sum2 = 0, dc_q = 0;
  for (std::size_t i = 0; i + floats <= sums_.size(); i += floats) {
    const float* s = &sums_[i];
    const float* s_dc = s + 3 * width;
    const float* q_dc = s_dc + channels;
    const double n = s_dc[2 * channels];
    for (std::size_t c = 0; c < channels; ++c) {
      dc_sum2 += double(s_dc[c]) * s_dc[c];
      dc_q += q_dc[c];
    }
    if (n < 3) continue;
    for (std::size_t j = 0; j < width; ++j) {
      const double qd = q_dc[j % channels];
      if (!(qd > 0)) continue;
      const double sd = s_dc[j % channels];
      const double beta = s[width + j] / qd;
      const double rest = s[j] - beta * sd;
      const double rest_q = std::max(0.0, s[2 * width + j] - double(s[width + j]) * s[width + j] / qd);
      band_sum2 += rest * rest;
      band_null += rest_q / (n - 1) * std::max(0.0, n - sd * sd / qd);
    }
  }
  BandDecision d;
  d.iteration = it;
  d.band = *candidate_;
  // No gradient left once the DC's part is taken out: no evidence, the band stays off.
  d.signal = band_null > 0 ? band_sum2 / band_null : 0.0;
  d.dc_signal = dc_q > 0 ? dc_sum2 / dc_q : 0.0;
  d.switched_on = d.signal >= options_.min_signal;
  return d;
}

std::optional<BandDecision> ColorBandGate::End(int it, bool rows_move) {
  if (!probing()) return std::nullopt;
  if (!rows_move && it - probe_from_ + 1 < options_.probe_iterations) return std::nullopt;
  BandDecision d = Decide(it);
  if (d.switched_on) accepted_ = *candidate_;
  candidate_.reset();
  probe_from_ = 0;
  sums_.clear();
  sums_.shrink_to_fit();
  decisions_.push_back(d);
  return d;
}

nlohmann::json ColorBandGate::ToJson() const {
  nlohmann::json decisions = nlohmann::json::array();
  for (const BandDecision& d : decisions_) decisions.push_back(d.ToJson());
  return {{"sh_degree", accepted_.sh},
          {"time_degree", accepted_.time},
          {"probe_from", probe_from_},
          {"decisions", decisions}};
}

void ColorBandGate::FromJson(const nlohmann::json& j, std::vector<float> sums,
                             std::size_t num_gaussians, const std::string& source) {
  try {
    accepted_ = {j.at("sh_degree").get<int>(), j.at("time_degree").get<int>()};
    probe_from_ = j.at("probe_from").get<int>();
    decisions_.clear();
    for (const nlohmann::json& d : j.at("decisions")) decisions_.push_back(BandDecision::FromJson(d));
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: corrupt checkpoint: colour band state: {}", source, e.what());
  }
  const bool degrees_ok = accepted_.sh >= 0 && accepted_.sh <= basis_.max_sh_degree &&
                          accepted_.time >= 0 &&
                          accepted_.time <= (temporal_ ? basis_.max_time_degree : 0) &&
                          (accepted_.time == 0 || accepted_.sh == basis_.max_sh_degree);
  if (!degrees_ok || probe_from_ < 0)
    Fail("{}: corrupt checkpoint: colour bands out of range (SH degree {}, time degree {}, "
         "probe from {})",
         source, accepted_.sh, accepted_.time, probe_from_);
  candidate_.reset();
  if (probing()) {
    candidate_ = NextBand(accepted_, basis_, temporal_);
    if (!candidate_ || sums.size() != num_gaussians * row_floats())
      Fail("{}: corrupt checkpoint: the colour-band probe from iteration {} has {} sums for {} "
           "Gaussians",
           source, probe_from_, sums.size(), num_gaussians);
  }
  sums_ = std::move(sums);
}

}  // namespace hdr4d::method
