#include "baselines/tone_mapper_kinds.h"

#include <memory>

#include "baselines/durand_tone_mapper.h"
#include "baselines/reinhard_tone_mapper.h"
#include "baselines/sigmoid_tone_mapper.h"
#include "baselines/static_mlp_tone_mapper.h"
#include "method/tonemap/tone_mapper_registry.h"

namespace hdr4d::baselines {
namespace {

template <typename Mapper>
std::unique_ptr<method::ToneMapper> Make(const method::ToneMapperConfig& config) {
  return std::make_unique<Mapper>(config);
}

}  // namespace

void RegisterToneMappers() {
  method::RegisterToneMapperKind("mlp", Make<StaticMlpToneMapper>);
  method::RegisterToneMapperKind("sigmoid", Make<SigmoidToneMapper>);
  method::RegisterToneMapperKind("reinhard", Make<ReinhardToneMapper>);
  method::RegisterToneMapperKind("durand", Make<DurandToneMapper>);
}

}  // namespace hdr4d::baselines
