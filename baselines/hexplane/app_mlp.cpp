#include "baselines/hexplane/app_mlp.h"

namespace hdr4d::baselines::hexplane {

std::vector<float> InitAppMlp(const AppMlpShape& shape, std::uint64_t seed) {
  const method::MlpShape layers = shape.Layers();
  std::vector<float> p(layers.NumParams());
  method::MlpInit(layers, seed, p.data());
  for (int k = 1; k <= layers.outputs(); ++k) p[p.size() - k] = 0.0f;  // zero_init of the last bias
  return p;
}

}  // namespace hdr4d::baselines::hexplane
