#include "method/optim/fused_adam_step.h"

#include <array>
#include <span>

#include "core/util/error.h"
#include "method/optim/densify.h"

namespace hdr4d::method {

GradientRowsDone StepModelRows(const std::vector<std::string>& groups, AdamRowStep* step) {
  HDR4D_CHECK(step != nullptr && groups.size() <= kModelGroups.size());
  if (groups.empty()) return {};
  int dc = -1, rest = -1;  // the parts whose rows the callback passes
  for (std::size_t k = 0; k < groups.size(); ++k) {
    if (groups[k] == kGroupFDc) dc = static_cast<int>(k);
    if (groups[k] == kGroupFRest) rest = static_cast<int>(k);
  }
  const std::size_t parts = groups.size();
  return [step, dc, rest, parts](std::int64_t b, std::int64_t e, const GradientRows& colour) {
    std::array<const float*, kModelGroups.size()> rows{};  // nullptr: the bound buffer
    if (dc >= 0) rows[dc] = colour.color_dc;
    if (rest >= 0) rows[rest] = colour.color_rest;
    step->StepRows(b, e, std::span<const float* const>(rows.data(), parts));
  };
}

}  // namespace hdr4d::method
