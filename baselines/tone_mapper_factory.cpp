#include "baselines/tone_mapper_factory.h"

#include <algorithm>

#include "baselines/durand_tone_mapper.h"
#include "baselines/reinhard_tone_mapper.h"
#include "baselines/sigmoid_tone_mapper.h"
#include "baselines/static_mlp_tone_mapper.h"
#include "core/error.h"
#include "method/tonemap/dynamic_tone_mapper.h"

namespace hdr4d::baselines {

const std::vector<std::string>& ToneMapperKinds() {
  static const std::vector<std::string> kinds = {"dtm", "mlp", "sigmoid", "reinhard", "durand"};
  return kinds;
}

std::unique_ptr<method::ToneMapper> MakeToneMapper(const method::ToneMapperConfig& config) {
  const auto& kinds = ToneMapperKinds();
  if (std::find(kinds.begin(), kinds.end(), config.kind) == kinds.end()) {
    std::string valid;
    for (const std::string& k : kinds) valid += (valid.empty() ? "" : ", ") + k;
    Fail("unknown tone mapper kind '{}' (valid kinds: {})", config.kind, valid);
  }
  const std::string problem = config.Validate();
  if (!problem.empty()) Fail("invalid tone mapper configuration: {}", problem);
  if (config.kind == "dtm") return std::make_unique<method::DynamicToneMapper>(config);
  if (config.kind == "mlp") return std::make_unique<StaticMlpToneMapper>(config);
  if (config.kind == "sigmoid") return std::make_unique<SigmoidToneMapper>(config);
  if (config.kind == "reinhard") return std::make_unique<ReinhardToneMapper>(config);
  HDR4D_CHECK(config.kind == "durand");
  return std::make_unique<DurandToneMapper>(config);
}

}  // namespace hdr4d::baselines
