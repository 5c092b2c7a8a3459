// Adds the baselines' tone-mapper kinds to the method's registry (tone_mapper_registry.h):
// mlp (static MLP, HDR-GS), sigmoid (HDR-HexPlane), reinhard, durand, after the built-in dtm.
#pragma once

namespace hdr4d::baselines {

// Idempotent and thread-safe; call once at start in every program that builds tone mappers by
// kind (the hdr4d app does it before reading its flags).
void RegisterToneMappers();

}  // namespace hdr4d::baselines
