#include "method/tonemap/tone_curve_samples.h"

#include <algorithm>

#include "core/util/error.h"
#include "method/tonemap/radiance_bank.h"

namespace hdr4d::method {

ToneCurveSamples SampleToneCurves(ToneMapper* tone_mapper,
                                  const std::vector<double>& times,
                                  int num_times,
                                  double x_min,
                                  double x_max,
                                  int samples) {
  HDR4D_CHECK(tone_mapper && samples >= 2 && x_max > x_min && num_times >= 1);
  if (!tone_mapper->pointwise()) {
    Fail(
        "tone-curves: the '{}' tone mapper works on whole images (a local operator), so it has "
        "no single curve to plot",
        tone_mapper->config().kind);
  }
  ToneCurveSamples s;
  s.times = times;
  s.x.resize(samples);
  for (int i = 0; i < samples; ++i) s.x[i] = x_min + (x_max - x_min) * i / (samples - 1);
  // The curve is g(log_hdr + log e): sample log_hdr = x at log e = 0, all channels at once.
  std::vector<float> in(std::size_t(samples) * 3), out(in.size());
  for (int i = 0; i < samples; ++i)
    for (int c = 0; c < 3; ++c) in[i * 3 + c] = static_cast<float>(s.x[i]);
  for (double t : times) {
    tone_mapper->BeginFrame({RadianceBank::TimeIndex(t, num_times), -1, 0.0f});
    tone_mapper->Map(in.data(), samples, out.data());
    std::vector<std::vector<double>> per_channel(3, std::vector<double>(samples));
    for (int i = 0; i < samples; ++i)
      for (int c = 0; c < 3; ++c) per_channel[c][i] = out[i * 3 + c];
    s.ldr.push_back(std::move(per_channel));
  }
  return s;
}

std::vector<FlatToneCurve> FindFlatToneCurves(ToneMapper* tone_mapper,
                                              int num_times,
                                              double x_min,
                                              double x_max,
                                              double tolerance) {
  std::vector<FlatToneCurve> flat;
  if (tone_mapper == nullptr || !tone_mapper->pointwise() || !(x_max > x_min)) return flat;
  const ToneCurveSamples s =
      SampleToneCurves(tone_mapper, {0.0, 0.5, 1.0}, num_times, x_min, x_max, 64);
  for (int c = 0; c < 3; ++c) {
    for (std::size_t k = 0; k < s.times.size(); ++k) {
      const std::vector<double>& y = s.ldr[k][c];
      const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
      if (*hi - *lo >= tolerance) continue;
      double mean = 0;
      for (double v : y) mean += v / y.size();
      flat.push_back({.channel = c, .time = s.times[k], .level = mean, .spread = *hi - *lo});
      break;
    }
  }
  return flat;
}

}  // namespace hdr4d::method
