#include "method/render/resolved_hdr_training.h"

namespace hdr4d::method {

nlohmann::json ResolvedHdrTraining::ToJson() const {
  return {{"hdr_colors", hdr_colors},
          {"ldr_gaussian", ldr_gaussian},
          {"ldr_pixel", ldr_pixel},
          {"hdr", hdr},
          {"hdr_head", hdr_head},
          {"final_ldr_from_pixels", final_ldr_from_pixels},
          {"pixel_log_epsilon", pixel_log_epsilon}};
}

}  // namespace hdr4d::method
