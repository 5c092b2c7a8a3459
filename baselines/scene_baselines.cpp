#include "baselines/scene_baselines.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "core/util/error.h"

namespace hdr4d::baselines {

using method::ColorMode;
using method::HdrTrainingOptions;
using method::Supervision;
using method::ToneMapperConfig;

const std::vector<std::string>& MethodNames() {
  static const std::vector<std::string> names = {"hdr4dgs", "4dgs", "4dgs-hdr", "hdr-gs"};
  return names;
}

HdrTrainingOptions MethodPreset(const std::string& name) {
  HdrTrainingOptions o;
  o.method = name;
  if (name == "hdr4dgs") {
    o.color_mode = ColorMode::kLogHdr;
    o.tone_mapper = ToneMapperConfig{};  // kind "dtm"
  } else if (name == "4dgs") {
    o.color_mode = ColorMode::kLdr;
    o.tone_mapper.reset();
    o.supervision = Supervision::kLdr;
  } else if (name == "4dgs-hdr") {
    o.color_mode = ColorMode::kLogHdr;
    o.tone_mapper.reset();
    o.supervision = Supervision::kHdr;
  } else if (name == "hdr-gs") {
    o.color_mode = ColorMode::kLogHdr;
    o.force_static = true;
    ToneMapperConfig tm;
    tm.kind = "mlp";
    o.tone_mapper = tm;
    o.pixel_branch = false;
    o.supervision = Supervision::kAuto;  // LDR + HDR where HDR ground truth exists
  } else {
    Fail("--method: unknown method '{}' (one of: {})", name, fmt::join(MethodNames(), ", "));
  }
  return o;
}

}  // namespace hdr4d::baselines
