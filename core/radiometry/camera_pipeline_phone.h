// The phone pipeline's content-adaptive parts.
//
// Tone curve. Each view gets a global curve fitted to its own histogram, as a phone's tone
// mapping adapts to the content: with x_lo and x_hi the view's low and high log-luminance
// percentiles after exposure (x = radiance * reference exposure * AE gain),
//   white (the shoulder: the curve reaches 1 there)  w = clamp(x_hi, 1e-3, 1e3)
//   mid (steepest point in log x, relative to w)     m = sqrt(clamp(x_lo / w, 1e-8, 0.25))
//   contrast                                          k = clamp(ln(toe) / ln(m), 0.4, 3)
// and y = filmic_{k,m}(x / w) (crf.h's FilmicCrf: (1 + m^k) u^k / (u^k + m^k), u = x / w),
// which puts the toe (y = m^k = toe = 0.02 when k is not clamped) at x_lo, the middle of the
// S-curve at the geometric centre of [x_lo, x_hi], and white at x_hi: the shoulder and the toe
// follow the content. The white point may exceed the sensor's nominal full scale (x = 1), as a
// phone's multi-frame HDR keeps highlights a single exposure clips.
//
// White balance. The white-balance gains drift over time, per camera with its own phase:
//   ln W_R = a sin(2 pi t / P + phi_c),  W_G = 1,  ln W_B = -ln W_R,
// phi_c = 2 pi frac(0.618034 c) for camera c, amplitude a, period P (normalised time).
#pragma once

#include <array>
#include <nlohmann/json.hpp>

#include "core/radiometry/frame_statistics.h"

namespace hdr4d {

inline constexpr double kPhoneToe = 0.02;

struct PhoneCurve {
  double white = 1, mid = 0.18, contrast = 1.5;
  nlohmann::json ToJson() const;
};

// exposure_gain: reference exposure (s) times the view's AE gain, > 0.
PhoneCurve FitPhoneCurve(const FrameStatistics& stats, double exposure_gain);

std::array<double, 3> WhiteBalanceDrift(int camera, double time, double amplitude, double period);

}  // namespace hdr4d
