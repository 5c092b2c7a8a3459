// Recovering a camera's response per colour channel from brackets of a static scene
// (several exposure times, same view): Debevec & Malik 1997, least squares on log exposure
// with a smoothness prior, solved as sparse normal equations with Eigen; or Robertson et al.
// 2003 (alternating maximum likelihood of radiances and curve).
// The result is the inverse response per 8-bit code, x(code) = exposure that produces the
// code, normalised so that x(128) = 1 (the curves are known only up to scale).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/image/image.h"

namespace hdr4d {

struct Bracket {
  Image image;          // display values in [0,1] (8/16-bit files as stored), same size each
  double exposure = 0;  // seconds, > 0
  std::string name;     // for messages (file path)
};

struct ResponseOptions {
  int samples = 200;       // pixel locations sampled over all stacks (Debevec)
  double smoothness = 30;  // lambda of the second-difference prior (Debevec)
  bool robertson = false;  // Robertson et al. instead: every pixel, alternating estimates
  int robertson_iterations = 30;
};

constexpr int kResponseCodes = 256;

struct CameraResponse {
  // Inverse response per channel: exposure (relative) of each code, x[128] = 1, non-decreasing.
  std::vector<std::array<double, kResponseCodes>> inverse;  // one per channel
  std::string method;
  // The exposure of `code` in channel c, linear interpolation on a continuous code value.
  double Linearize(int channel, double value01) const;
  // Linearize's inverse: the display value in [0,1] whose exposure is `exposure` (the first
  // code of a flat run; 0 below the curve, 1 above it).
  double Encode(int channel, double exposure) const;
};

// The code (0..255) of a display value in [0,1].
int CodeOf(float value01);

// Recovers the response from one or more stacks (each a vector of brackets of one static view).
// Throws hdr4d::Error naming the bracket for mismatched sizes or channel counts, a
// non-positive or repeated exposure, or fewer than two brackets.
CameraResponse RecoverResponse(const std::vector<std::vector<Bracket>>& stacks,
                               const ResponseOptions& options = {});

// Writes code,r,g,b (the inverse response per code) as CSV (TableCrf::FromCsv reads a column).
void WriteResponseCsv(const std::string& path, const CameraResponse& response);
// A log-exposure vs code plot of each channel (PNG or SVG by extension).
void WriteResponsePlot(const std::string& path, const CameraResponse& response);

}  // namespace hdr4d
