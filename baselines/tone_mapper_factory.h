// Builds any tone mapper by kind: the Dynamic Tone Mapper and every baseline.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "method/tonemap/tone_mapper.h"

namespace hdr4d::baselines {

// Every kind MakeToneMapper knows, the method's first: dtm, mlp, sigmoid, reinhard, durand.
const std::vector<std::string>& ToneMapperKinds();

// Throws hdr4d::Error for an unknown kind (the message lists the valid ones) or an invalid
// configuration (the message names the field).
std::unique_ptr<method::ToneMapper> MakeToneMapper(const method::ToneMapperConfig& config);

}  // namespace hdr4d::baselines
