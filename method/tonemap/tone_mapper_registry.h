// The one factory of tone mappers, by kind (ToneMapperConfig::kind). The Dynamic Tone Mapper is
// built in. The paper's baseline mappers live in baselines/ (which links this target, never the
// other way round) and add their kinds with baselines::RegisterToneMappers(); programs that
// link baselines call it once at start (the hdr4d app, the benchmark harness, their tests). The
// trainer and the run readers ask here, so nobody hands them a factory
// (docs/ARCHITECTURE.md, "Tone mappers").
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

using ToneMapperMaker = std::unique_ptr<ToneMapper> (*)(const ToneMapperConfig&);

// Adds `kind` (or replaces its maker); thread-safe, idempotent for the same maker.
void RegisterToneMapperKind(const std::string& kind, ToneMapperMaker make);

// The registered kinds in registration order: "dtm" first.
std::vector<std::string> ToneMapperKinds();

// Throws hdr4d::Error for an unregistered kind (the message lists the registered ones and says
// where the baseline kinds come from) or an invalid configuration (the message names the field).
std::unique_ptr<ToneMapper> MakeToneMapper(const ToneMapperConfig& config);

}  // namespace hdr4d::method
