// Adam's visible rows (adam.h, "Visible rows"; issue 55): a row step touches only the rows with a
// gradient, and a row's moments are caught up on the steps it missed when it is seen again.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/util/error.h"
#include "method/optim/adam.h"

namespace hdr4d::method {
namespace {

// Decay powers tabulated up to this gap; beyond it std::pow (a Gaussian unseen that long).
constexpr std::int64_t kDecayTable = 4096;

// True when every bit of the row's first `n` gradients is zero: the view did not see it.
bool ZeroGradientRow(const float* g, std::size_t n) {
  std::uint32_t bits = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t b;
    std::memcpy(&b, g + i, sizeof(b));
    bits |= b;
  }
  return bits == 0;
}

}  // namespace

detail::DecayPowers::DecayPowers(double beta) : beta_(beta), table_(kDecayTable) {
  for (std::int64_t k = 0; k < kDecayTable; ++k)
    table_[k] = static_cast<float>(std::pow(beta, static_cast<double>(k)));
}

float detail::DecayPowers::operator()(std::int64_t k) const {
  if (k < kDecayTable) return table_[static_cast<std::size_t>(k)];
  return static_cast<float>(std::pow(beta_, static_cast<double>(k)));
}

namespace {
// The k zero-gradient steps a row missed: m <- beta1 m and v <- beta2 v, k times.
void CatchUpMomentsRow(float* m, float* v, std::size_t width, std::int64_t k,
                       const detail::DecayPowers& decay1, const detail::DecayPowers& decay2) {
  const float f1 = decay1(k), f2 = decay2(k);
  for (std::size_t i = 0; i < width; ++i) {
    m[i] *= f1;
    v[i] *= f2;
  }
}
}  // namespace

void Adam::CatchUp(State& s) const {
  if (s.seen.empty()) return;
  const std::size_t rows = s.seen.size();
  HDR4D_CHECK(s.m.size() % rows == 0);
  const std::size_t width = s.m.size() / rows;
  for (std::size_t r = 0; r < rows; ++r) {
    const std::int64_t k = s.step - s.seen[r];
    if (k > 0) CatchUpMomentsRow(s.m.data() + r * width, s.v.data() + r * width, width, k, decay1_, decay2_);
  }
  s.seen.clear();
}

void Adam::CatchUpAll() {
  for (State& s : groups_) CatchUp(s);
}

void Adam::SetVisibleRows(bool on) {
  if (!on) CatchUpAll();
  visible_rows_ = on;
}

bool Adam::AnyRowBehind() const {
  for (const State& s : groups_) {
    if (!s.seen.empty()) return true;
  }
  return false;
}

std::int64_t Adam::RowStep(const std::string& name, std::size_t row) const {
  const State& s = Find(name);
  if (s.seen.empty()) return s.step;
  HDR4D_CHECK(row < s.seen.size());
  return s.seen[row];
}

// Runs of consecutive rows with a gradient (a model in time order sees runs of them) are caught
// up and then stepped by one call of the kernel; rows without one are not read further.
bool AdamRowStep::StepVisibleRows(const Part& part, std::int64_t begin, std::int64_t end,
                                  const float* g) {
  const std::size_t width = part.width;
  const std::size_t columns = std::min(part.columns, width);
  if (columns == 0) return true;
  bool finite = true;
  std::int64_t r = begin;
  while (r < end) {
    while (r < end && ZeroGradientRow(g + (r - begin) * width, columns)) ++r;
    const std::int64_t run = r;
    for (; r < end && !ZeroGradientRow(g + (r - begin) * width, columns); ++r) {
      // Steps missed since the row's moments were last brought up: this step is part.step.
      const std::int64_t k = part.step - 1 - part.seen[r];
      if (k > 0)
        CatchUpMomentsRow(part.m + r * width, part.v + r * width, columns, k, *part.decay1,
                         *part.decay2);
      part.seen[r] = part.step;
    }
    if (run == r) continue;
    const std::size_t at = static_cast<std::size_t>(run) * width;
    const float* gr = g + (run - begin) * width;
    if (columns == width) {
      finite &= detail::AdamUpdate(part.params + at, gr, part.m + at, part.v + at,
                                   static_cast<std::size_t>(r - run) * width, part.constants);
    } else {
      for (std::int64_t row = 0; row < r - run; ++row) {
        const std::size_t o = row * width;
        finite &= detail::AdamUpdate(part.params + at + o, gr + o, part.m + at + o,
                                     part.v + at + o, columns, part.constants);
      }
    }
  }
  return finite;
}

}  // namespace hdr4d::method
