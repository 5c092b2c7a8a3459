#include "method/tonemap/tone_mapper_registry.h"

#include <mutex>
#include <utility>

#include "core/util/error.h"
#include "method/tonemap/dynamic_tone_mapper.h"

namespace hdr4d::method {
namespace {

std::unique_ptr<ToneMapper> MakeDynamicToneMapper(const ToneMapperConfig& config) {
  return std::make_unique<DynamicToneMapper>(config);
}

struct Registry {
  std::mutex mutex;
  std::vector<std::pair<std::string, ToneMapperMaker>> kinds{{"dtm", MakeDynamicToneMapper}};
};

Registry& TheRegistry() {
  static Registry registry;
  return registry;
}

}  // namespace

void RegisterToneMapperKind(const std::string& kind, ToneMapperMaker make) {
  HDR4D_CHECK(!kind.empty() && make != nullptr);
  Registry& r = TheRegistry();
  std::lock_guard lock(r.mutex);
  for (auto& [name, maker] : r.kinds) {
    if (name == kind) {
      maker = make;
      return;
    }
  }
  r.kinds.emplace_back(kind, make);
}

std::vector<std::string> ToneMapperKinds() {
  Registry& r = TheRegistry();
  std::lock_guard lock(r.mutex);
  std::vector<std::string> names;
  for (const auto& entry : r.kinds) names.push_back(entry.first);
  return names;
}

std::unique_ptr<ToneMapper> MakeToneMapper(const ToneMapperConfig& config) {
  ToneMapperMaker make = nullptr;
  std::string valid;
  {
    Registry& r = TheRegistry();
    std::lock_guard lock(r.mutex);
    for (const auto& [name, maker] : r.kinds) {
      valid += (valid.empty() ? "" : ", ") + name;
      if (name == config.kind) make = maker;
    }
  }
  if (make == nullptr) {
    Fail(
        "unknown tone mapper kind '{}' (valid kinds: {}; the baselines' kinds mlp, sigmoid, "
        "reinhard and durand are added by baselines::RegisterToneMappers)",
        config.kind, valid);
  }
  const std::string problem = config.Validate();
  if (!problem.empty()) Fail("invalid tone mapper configuration: {}", problem);
  return make(config);
}

}  // namespace hdr4d::method
