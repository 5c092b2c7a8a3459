// What a bracket's code value says about the radiance, and how surely: the black level and read
// noise estimated from the brackets themselves, the code where the sensor saturates, and the
// weight of one bracket's radiance estimate (inverse variance, falling to zero near black and
// near saturation). Both Debevec and Robertson fusion use it.
#pragma once

#include <vector>

#include "calibration/response_recovery.h"

namespace hdr4d {

struct ChannelNoise {
  double black = 0;        // code of zero light (a pedestal; 0 for most encoded images)
  double read_sigma = 0.5; // noise around the black level, in codes (>= quantisation's 0.5)
  double saturation = kResponseCodes - 1;  // highest code the sensor reaches
  bool floor_found = false;  // a pile of pixels at the black level was seen (else black = 0)
};

// One entry per channel. The floor is read from the shortest bracket: when it holds a peak of
// pixels at its lowest codes (no light reached them), that peak is the black level and its
// spread below the peak the read noise; otherwise black = 0 and noise = quantisation.
std::vector<ChannelNoise> EstimateBracketNoise(const std::vector<Bracket>& brackets);

// The weight of radiance x(code)/t from a bracket of exposure t in one channel: the inverse of
// its variance, (t / x'(code))^2 / (read_sigma^2 + 1/12), tapered to zero within a few noise
// widths of the black level and within a few codes of saturation. 0 for unusable codes.
double BracketWeight(const ChannelNoise& noise, const std::array<double, kResponseCodes>& inverse,
                     double value01, double exposure);

// True where the code is far enough from black and saturation to be trusted at all.
bool UsableCode(const ChannelNoise& noise, double value01);

}  // namespace hdr4d
