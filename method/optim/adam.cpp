// Adam. The element update is written with Highway and compiled once per x86 target (AVX-512,
// AVX2, the baseline), picked at run time: without -fno-math-errno the compiler will not
// vectorise std::sqrt, and the scalar loop was compute-bound (docs/history/engine-speed.md).
#include "method/optim/adam.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <ostream>

#include "core/files/binary_stream.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/optim/permute_rows.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "method/optim/adam.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace hdr4d::method {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The update of elements [0, n). The last partial vector uses masked loads and stores, so every
// element goes through the same vector operations wherever it lies. A vector whose gradient holds
// a NaN or an infinity is left as it is; the result says whether there was one.
bool AdamKernel(float* HWY_RESTRICT p,
                const float* HWY_RESTRICT g,
                float* HWY_RESTRICT m,
                float* HWY_RESTRICT v,
                std::size_t n,
                const detail::StepConstants& c) {
  const hn::ScalableTag<float> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto w1 = hn::Set(d, c.w1);
  const auto beta2 = hn::Set(d, c.beta2);
  const auto w2 = hn::Set(d, c.w2);
  const auto inv_bias2_sqrt = hn::Set(d, c.inv_bias2_sqrt);
  const auto eps = hn::Set(d, c.eps);
  const auto neg_step = hn::Set(d, -c.step_size);
  auto update = [&](auto gi, auto mi, auto vi, auto pi, auto store) {
    mi = hn::MulAdd(w1, hn::Sub(gi, mi), mi);                  // m + (1 - beta1)(g - m)
    vi = hn::MulAdd(hn::Mul(w2, gi), gi, hn::Mul(vi, beta2));  // beta2 v + (1 - beta2) g^2
    // sqrt(v_hat) as sqrt(v) times a per-step constant: one division per value, not two (the
    // divider is the kernel's bottleneck on AVX-512; the result moves by at most an ulp).
    const auto denom = hn::MulAdd(hn::Sqrt(vi), inv_bias2_sqrt, eps);
    pi = hn::MulAdd(neg_step, hn::Div(mi, denom), pi);
    store(mi, vi, pi);
  };
  // g = m = v = +0 leaves p, m and v exactly as they are (p + (-step_size) (0 / eps) = p), so
  // such vectors are skipped: coefficients of SH degrees not yet active, never-touched rows.
  const hn::RebindToUnsigned<decltype(d)> du;
  auto all_zero = [&](auto gi, auto mi, auto vi) {
    const auto bits = hn::Or(hn::Or(hn::BitCast(du, gi), hn::BitCast(du, mi)), hn::BitCast(du, vi));
    return hn::AllTrue(du, hn::Eq(bits, hn::Zero(du)));
  };
  const auto exponent = hn::Set(du, 0x7f800000u);
  auto finite = [&](auto gi) {
    return hn::AllFalse(du, hn::Eq(hn::And(hn::BitCast(du, gi), exponent), exponent));
  };
  bool all_finite = true;
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    const auto gi = hn::LoadU(d, g + i);
    const auto mi = hn::LoadU(d, m + i);
    const auto vi = hn::LoadU(d, v + i);
    if (all_zero(gi, mi, vi)) continue;
    if (!finite(gi)) {
      all_finite = false;
      continue;
    }
    update(gi, mi, vi, hn::LoadU(d, p + i), [&](auto mi, auto vi, auto pi) {
      hn::StoreU(mi, d, m + i);
      hn::StoreU(vi, d, v + i);
      hn::StoreU(pi, d, p + i);
    });
  }
  if (i < n) {
    const auto mask = hn::FirstN(d, n - i);
    const auto gi = hn::MaskedLoad(mask, d, g + i);
    if (!finite(gi)) return false;
    update(gi, hn::MaskedLoad(mask, d, m + i), hn::MaskedLoad(mask, d, v + i),
           hn::MaskedLoad(mask, d, p + i), [&](auto mi, auto vi, auto pi) {
             hn::BlendedStore(mi, mask, d, m + i);
             hn::BlendedStore(vi, mask, d, v + i);
             hn::BlendedStore(pi, mask, d, p + i);
           });
  }
  return all_finite;
}

// True when no value has an all-ones exponent (NaN or infinity). Sixteen lanes at a time, with
// one early exit per 1024 values (the baseline build's loop was 4 lanes wide).
bool FiniteKernel(const float* HWY_RESTRICT values, std::size_t n) {
  const hn::ScalableTag<std::uint32_t> du;
  const std::size_t lanes = hn::Lanes(du);
  const auto exponent = hn::Set(du, 0x7f800000u);
  const auto* bits = reinterpret_cast<const std::uint32_t*>(values);
  auto bad = hn::Zero(du);
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    bad = hn::Or(bad,
                 hn::VecFromMask(du, hn::Eq(hn::And(hn::LoadU(du, bits + i), exponent), exponent)));
    if ((i & 1023) == 0 && !hn::AllTrue(du, hn::Eq(bad, hn::Zero(du)))) return false;
  }
  if (i < n) {
    const auto mask = hn::FirstN(du, n - i);
    const auto tail = hn::MaskedLoad(mask, du, bits + i);
    bad = hn::Or(bad, hn::VecFromMask(du, hn::Eq(hn::And(tail, exponent), exponent)));
  }
  return hn::AllTrue(du, hn::Eq(bad, hn::Zero(du)));
}

}  // namespace HWY_NAMESPACE
}  // namespace hdr4d::method
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hdr4d::method {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the Adam state format is little-endian; add byte swapping for this platform");

constexpr char kMagic[8] = {'H', 'D', 'R', '4', 'D', 'A', 'D', 'M'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kVersionRowSteps = 2;  // visible rows: each row's step
// Sanity limits for reading: a corrupt count must give an error, not a huge allocation.
constexpr std::uint32_t kMaxGroups = 1u << 16;
constexpr std::uint32_t kMaxNameLength = 4096;
constexpr std::uint64_t kMaxGroupSize = std::uint64_t{1} << 40;
constexpr std::int64_t kGrain = 16384;

}  // namespace

HWY_EXPORT(AdamKernel);
HWY_EXPORT(FiniteKernel);

namespace {
bool ChunkFinite(const float* values, std::size_t size) {
  return HWY_DYNAMIC_DISPATCH(FiniteKernel)(values, size);
}
}  // namespace

bool detail::AdamUpdate(float* p, const float* g, float* m, float* v, std::size_t n,
                        const StepConstants& c) {
  return HWY_DYNAMIC_DISPATCH(AdamKernel)(p, g, m, v, n, c);
}

// ---- AdamOptions
// ---------------------------------------------------------------------------------

std::string AdamOptions::Validate() const {
  if (!(beta1 >= 0.0 && beta1 < 1.0)) return fmt::format("beta1 must be in [0, 1), got {}", beta1);
  if (!(beta2 >= 0.0 && beta2 < 1.0)) return fmt::format("beta2 must be in [0, 1), got {}", beta2);
  if (!(eps > 0.0) || !std::isfinite(eps)) {
    return fmt::format("eps must be positive and finite, got {}", eps);
  }
  return "";
}

// ---- Groups
// --------------------------------------------------------------------------------------

Adam::Adam(const AdamOptions& options) : options_(options) {
  const std::string problem = options.Validate();
  if (!problem.empty()) Fail("Adam options: {}", problem);
  decay1_ = detail::DecayPowers(options_.beta1);
  decay2_ = detail::DecayPowers(options_.beta2);
}

Adam::State& Adam::Find(const std::string& name) {
  for (State& s : groups_) {
    if (s.group.name == name) return s;
  }
  std::fprintf(stderr, "hdr4d: Adam has no parameter group '%s'\n", name.c_str());
  HDR4D_CHECK(false && "unknown Adam group");
  std::abort();
}

const Adam::State& Adam::Find(const std::string& name) const {
  return const_cast<Adam*>(this)->Find(name);
}

void Adam::AddGroup(const AdamGroup& group) {
  HDR4D_CHECK(!group.name.empty());
  HDR4D_CHECK(!HasGroup(group.name));
  HDR4D_CHECK(group.size == 0 || group.params != nullptr);
  State state;
  state.group = group;
  state.m.assign(group.size, 0.0f);
  state.v.assign(group.size, 0.0f);
  groups_.push_back(std::move(state));
}

bool Adam::HasGroup(const std::string& name) const {
  return std::any_of(groups_.begin(), groups_.end(),
                     [&](const State& s) { return s.group.name == name; });
}

std::vector<std::string> Adam::GroupNames() const {
  std::vector<std::string> names;
  for (const State& s : groups_) names.push_back(s.group.name);
  return names;
}

const AdamGroup& Adam::group(const std::string& name) const { return Find(name).group; }

void Adam::SetBuffers(const std::string& name,
                      float* params,
                      const float* grads,
                      std::size_t size) {
  State& s = Find(name);
  HDR4D_CHECK(size == s.m.size());
  HDR4D_CHECK(size == 0 || params != nullptr);
  s.group.params = params;
  s.group.grads = grads;
  s.group.size = size;
}

void Adam::SetLearningRate(const std::string& name, float lr) { Find(name).group.lr = lr; }

float Adam::LearningRate(const std::string& name) const { return Find(name).group.lr; }

std::int64_t Adam::StepCount(const std::string& name) const { return Find(name).step; }

const std::vector<float>& Adam::FirstMoment(const std::string& name) const { return Find(name).m; }

const std::vector<float>& Adam::SecondMoment(const std::string& name) const { return Find(name).v; }

// ---- The update
// ----------------------------------------------------------------------------------

detail::StepConstants Adam::NextStep(State& state) {
  ++state.step;
  const double step = static_cast<double>(state.step);
  const double bias1 = 1.0 - std::pow(options_.beta1, step);
  const double bias2 = 1.0 - std::pow(options_.beta2, step);
  detail::StepConstants c;
  c.step_size = static_cast<float>(static_cast<double>(state.group.lr) / bias1);
  c.inv_bias2_sqrt = static_cast<float>(1.0 / std::sqrt(bias2));
  c.w1 = static_cast<float>(1.0 - options_.beta1);
  c.beta2 = static_cast<float>(options_.beta2);
  c.w2 = static_cast<float>(1.0 - options_.beta2);
  c.eps = static_cast<float>(options_.eps);
  return c;
}

void Adam::StepState(State& state) {
  CatchUp(state);  // visible rows: every row is stepped here
  const AdamGroup& g = state.group;
  HDR4D_CHECK(g.size == state.m.size());
  HDR4D_CHECK(g.size == 0 || (g.params != nullptr && g.grads != nullptr));
  const detail::StepConstants c = NextStep(state);
  if (g.size == 0) return;
  float* params = g.params;
  const float* grads = g.grads;
  float* m = state.m.data();
  float* v = state.v.data();
  ParallelForChunks(static_cast<std::int64_t>(g.size), kGrain,
                    [&](std::int64_t begin, std::int64_t end) {
                      HWY_DYNAMIC_DISPATCH(AdamKernel)
                      (params + begin, grads + begin, m + begin, v + begin,
                       static_cast<std::size_t>(end - begin), c);
                    });
}

AdamRowStep Adam::BeginRowStep(const std::vector<std::string>& names, std::size_t rows) {
  AdamRowStep step;
  step.rows_ = rows;
  step.bad_ = std::make_unique<std::atomic<bool>[]>(names.size());
  for (std::size_t k = 0; k < names.size(); ++k) {
    State& s = Find(names[k]);
    const AdamGroup& g = s.group;
    HDR4D_CHECK(g.size == s.m.size());
    HDR4D_CHECK(g.size == 0 || g.params != nullptr);  // gradients may come only as rows
    HDR4D_CHECK(rows > 0 ? g.size % rows == 0 : g.size == 0);
    const std::size_t width = rows > 0 ? g.size / rows : 0;
    if (!visible_rows_) CatchUp(s);
    HDR4D_CHECK(s.seen.empty() || s.seen.size() == rows);
    if (visible_rows_ && s.seen.size() != rows) s.seen.assign(rows, s.step);
    step.parts_.push_back(
        {g.name, g.params, g.grads, s.m.data(), s.v.data(), width, width, NextStep(s)});
    if (visible_rows_) {
      AdamRowStep::Part& part = step.parts_.back();
      part.seen = s.seen.data();
      part.step = s.step;
      part.decay1 = &decay1_;
      part.decay2 = &decay2_;
    }
    step.bad_[k] = false;
  }
  return step;
}

void AdamRowStep::StepRows(std::int64_t begin,
                           std::int64_t end,
                           std::span<const float* const> grad_rows) {
  HDR4D_CHECK(begin >= 0 && begin <= end && static_cast<std::size_t>(end) <= rows_);
  HDR4D_CHECK(grad_rows.empty() || grad_rows.size() == parts_.size());
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    const Part& part = parts_[k];
    const std::size_t first = static_cast<std::size_t>(begin) * part.width;
    const std::size_t n = static_cast<std::size_t>(end - begin) * part.width;
    if (n == 0) continue;
    const float* g = !grad_rows.empty() ? grad_rows[k] : nullptr;
    if (g == nullptr) {
      HDR4D_CHECK(part.grads != nullptr);  // neither rows given nor a gradient buffer bound
      g = part.grads + first;
    }
    bool finite = true;
    if (part.seen != nullptr) {
      finite = StepVisibleRows(part, begin, end, g);
    } else if (part.columns >= part.width) {
      finite = HWY_DYNAMIC_DISPATCH(AdamKernel)(part.params + first, g, part.m + first,
                                                part.v + first, n, part.constants);
    } else if (part.columns > 0) {
      for (std::size_t row = 0; row < static_cast<std::size_t>(end - begin); ++row) {
        const std::size_t at = first + row * part.width;
        finite &= HWY_DYNAMIC_DISPATCH(AdamKernel)(part.params + at, g + row * part.width,
                                                   part.m + at, part.v + at, part.columns,
                                                   part.constants);
      }
    }
    if (!finite) bad_[k].store(true, std::memory_order_relaxed);
  }
}

void AdamRowStep::LimitColumns(const std::string& group, std::size_t columns) {
  for (Part& part : parts_) {
    if (part.name == group) part.columns = std::min(columns, part.width);
  }
}

std::string AdamRowStep::FirstNonFinite() const {
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    if (bad_[k].load()) return parts_[k].name;
  }
  return "";
}

void Adam::Step() {
  for (State& s : groups_) StepState(s);
}

void Adam::StepGroup(const std::string& name) { StepState(Find(name)); }

std::string Adam::FirstNonFiniteGradient() const { return FirstNonFiniteGradient(GroupNames()); }

std::string Adam::FirstNonFiniteGradient(const std::vector<std::string>& only) const {
  for (const State& s : groups_) {
    if (std::find(only.begin(), only.end(), s.group.name) == only.end()) continue;
    if (s.group.size > 0 && s.group.grads != nullptr && !AllFinite(s.group.grads, s.group.size)) {
      return s.group.name;
    }
  }
  return "";
}

// ---- Surgery
// -------------------------------------------------------------------------------------

void Adam::ResizeGroup(const std::string& name, std::size_t new_size) {
  State& s = Find(name);
  CatchUp(s);
  s.m.resize(new_size, 0.0f);
  s.v.resize(new_size, 0.0f);
  s.group = AdamGroup{s.group.name, nullptr, nullptr, new_size, s.group.lr};
}

void Adam::GatherGroup(const std::string& name,
                       const std::vector<std::uint32_t>& keep,
                       std::size_t row_width) {
  State& s = Find(name);
  CatchUp(s);
  HDR4D_CHECK(row_width > 0 && s.m.size() % row_width == 0);
  const std::size_t rows = s.m.size() / row_width;
  for (const std::uint32_t r : keep) HDR4D_CHECK(r < rows);
  if (std::is_sorted(keep.begin(), keep.end()) &&
      std::adjacent_find(keep.begin(), keep.end()) == keep.end()) {
    // Densification keeps rows in increasing order: keep[k] >= k, so moving each row forward in
    // order never overwrites one still to be read, and no second pair of moment buffers (the
    // size of the whole group) is allocated while the first is alive.
    for (std::size_t k = 0; k < keep.size(); ++k) {
      const std::size_t from = static_cast<std::size_t>(keep[k]) * row_width;
      if (from == k * row_width) continue;
      std::copy_n(s.m.begin() + from, row_width, s.m.begin() + k * row_width);
      std::copy_n(s.v.begin() + from, row_width, s.v.begin() + k * row_width);
    }
    s.m.resize(keep.size() * row_width);
    s.v.resize(keep.size() * row_width);
  } else {
    std::vector<float> m(keep.size() * row_width), v(keep.size() * row_width);
    for (std::size_t k = 0; k < keep.size(); ++k) {
      const std::size_t from = static_cast<std::size_t>(keep[k]) * row_width;
      std::copy_n(s.m.begin() + from, row_width, m.begin() + k * row_width);
      std::copy_n(s.v.begin() + from, row_width, v.begin() + k * row_width);
    }
    s.m = std::move(m);
    s.v = std::move(v);
  }
  s.group = AdamGroup{s.group.name, nullptr, nullptr, s.m.size(), s.group.lr};
}

void Adam::AppendRows(const std::string& name, std::size_t count, std::size_t row_width) {
  State& s = Find(name);
  HDR4D_CHECK(row_width > 0 && s.m.size() % row_width == 0);
  ResizeGroup(name, s.m.size() + count * row_width);
}

void Adam::ReserveGroup(const std::string& name, std::size_t size) {
  State& s = Find(name);
  s.m.reserve(size);
  s.v.reserve(size);
}

void Adam::PermuteRows(const std::string& name,
                       const std::vector<std::uint32_t>& order,
                       std::size_t row_width) {
  State& s = Find(name);
  CatchUp(s);
  HDR4D_CHECK(row_width > 0 && s.m.size() == order.size() * row_width);
  HDR4D_CHECK(IsPermutation(order));
  PermuteRowsInPlace(s.m.data(), row_width, order);
  PermuteRowsInPlace(s.v.data(), row_width, order);
}

void Adam::ResetMoments(const std::string& name) {
  State& s = Find(name);
  CatchUp(s);
  std::fill(s.m.begin(), s.m.end(), 0.0f);
  std::fill(s.v.begin(), s.v.end(), 0.0f);
}

void Adam::ResetMoments(const std::string& name,
                        const std::vector<std::uint32_t>& rows,
                        std::size_t row_width) {
  State& s = Find(name);
  CatchUp(s);
  HDR4D_CHECK(row_width > 0 && s.m.size() % row_width == 0);
  const std::size_t count = s.m.size() / row_width;
  for (std::uint32_t r : rows) {
    HDR4D_CHECK(r < count);
    std::fill_n(s.m.begin() + static_cast<std::size_t>(r) * row_width, row_width, 0.0f);
    std::fill_n(s.v.begin() + static_cast<std::size_t>(r) * row_width, row_width, 0.0f);
  }
}

// ---- Save / load
// ---------------------------------------------------------------------------------

void Adam::Save(std::ostream& out) const {
  HashingWriter w(out);
  w.Bytes(kMagic, sizeof(kMagic));
  const bool rows_behind = AnyRowBehind();
  w.Value(rows_behind ? kVersionRowSteps : kVersion);
  w.ResetHash();
  w.Value(options_.beta1);
  w.Value(options_.beta2);
  w.Value(options_.eps);
  w.Value(static_cast<std::uint32_t>(groups_.size()));
  for (const State& s : groups_) {
    w.Value(static_cast<std::uint32_t>(s.group.name.size()));
    w.Bytes(s.group.name.data(), s.group.name.size());
    w.Value(static_cast<std::uint64_t>(s.m.size()));
    w.Value(s.step);
    w.Value(s.group.lr);
    w.Bytes(s.m.data(), s.m.size() * sizeof(float));
    w.Bytes(s.v.data(), s.v.size() * sizeof(float));
    if (rows_behind) {
      w.Value(static_cast<std::uint64_t>(s.seen.size()));
      w.Bytes(s.seen.data(), s.seen.size() * sizeof(std::int64_t));
    }
  }
  const std::uint64_t hash = w.hash();
  w.Value(hash);
}

std::uint64_t Adam::SavedSize() const {
  // The fields of Save, in order: magic, version, three f64 options, the group count; per group
  // the name's length and bytes, size, step, learning rate and both moments; the checksum.
  std::uint64_t bytes = sizeof(kMagic) + sizeof(kVersion) + 3 * sizeof(double) +
                        sizeof(std::uint32_t) + sizeof(std::uint64_t);
  for (const State& s : groups_) {
    bytes += sizeof(std::uint32_t) + s.group.name.size() + sizeof(std::uint64_t) +
             sizeof(s.step) + sizeof(s.group.lr) + 2 * s.m.size() * sizeof(float);
    if (AnyRowBehind())
      bytes += sizeof(std::uint64_t) + s.seen.size() * sizeof(std::int64_t);
  }
  return bytes;
}

namespace {

// The header of a saved state: magic, version and the options (the checksum starts after the
// version).
AdamOptions ReadAdamHeader(HashingReader& r, const std::string& source,
                           std::uint32_t* version_read) {
  char magic[sizeof(kMagic)];
  r.Bytes(magic, sizeof(magic), "the header");
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) {
    Fail("{}: not an Adam optimiser state (bad magic; expected \"HDR4DADM\")", source);
  }
  const auto version = r.Value<std::uint32_t>("the version");
  if (version != kVersion && version != kVersionRowSteps) {
    Fail("{}: Adam state version {} is not supported (this build reads versions {} and {})",
         source, version, kVersion, kVersionRowSteps);
  }
  *version_read = version;
  r.ResetHash();
  AdamOptions options;
  options.beta1 = r.Value<double>("beta1");
  options.beta2 = r.Value<double>("beta2");
  options.eps = r.Value<double>("eps");
  return options;
}

}  // namespace

Adam::State Adam::ReadGroupState(HashingReader& r,
                                 std::uint32_t index,
                                 const std::vector<State>& before,
                                 std::uint32_t version) {
  const std::string& source = r.source();
  State s;
  const std::string group_what = fmt::format("group {}", index);
  const auto name_length = r.Value<std::uint32_t>(group_what + " name length");
  if (name_length == 0 || name_length > kMaxNameLength) {
    Fail("{}: Adam state group {} has a name of length {} (must be 1..{}: corrupt)", source, index,
         name_length, kMaxNameLength);
  }
  s.group.name.resize(name_length);
  r.Bytes(s.group.name.data(), name_length, group_what + " name");
  const std::string what = fmt::format("group '{}'", s.group.name);
  for (const State& other : before) {
    if (other.group.name == s.group.name) {
      Fail("{}: Adam state has two groups named '{}'", source, s.group.name);
    }
  }
  const auto size = r.Value<std::uint64_t>(what + " size");
  if (size > kMaxGroupSize) {
    Fail("{}: Adam state {} claims {} values (corrupt)", source, what, size);
  }
  s.step = r.Value<std::int64_t>(what + " step count");
  s.group.lr = r.Value<float>(what + " learning rate");
  s.m = r.Floats(size, what + " first moments");
  s.v = r.Floats(size, what + " second moments");
  s.group.size = static_cast<std::size_t>(size);
  if (version == kVersionRowSteps) {
    const auto rows = r.Value<std::uint64_t>(what + " row count");
    if (rows > size || (rows > 0 && size % rows != 0)) {
      Fail("{}: Adam state {} has {} row steps for {} values (corrupt)", source, what, rows, size);
    }
    s.seen.resize(rows);
    r.Bytes(s.seen.data(), rows * sizeof(std::int64_t), what + " row steps");
  }
  return s;
}

void Adam::CheckLoadedValues(const AdamOptions& options,
                             const std::vector<State>& groups,
                             const std::string& source) {
  const std::string problem = options.Validate();
  if (!problem.empty()) Fail("{}: Adam state has invalid options: {}", source, problem);
  for (const State& s : groups) {
    if (s.step < 0) {
      Fail("{}: Adam state group '{}' has a negative step count {}", source, s.group.name, s.step);
    }
    for (std::size_t row = 0; row < s.seen.size(); ++row) {
      if (s.seen[row] < 0 || s.seen[row] > s.step) {
        Fail("{}: Adam state group '{}' row {} was last stepped at {}, outside 0..{} (corrupt)",
             source, s.group.name, row, s.seen[row], s.step);
      }
    }
    if (!(s.group.lr >= 0.0f) || !std::isfinite(s.group.lr)) {
      Fail("{}: Adam state group '{}' has an invalid learning rate {}", source, s.group.name,
           s.group.lr);
    }
    for (std::size_t k = 0; k < s.m.size(); ++k) {
      if (!std::isfinite(s.m[k]) || !std::isfinite(s.v[k]) || !(s.v[k] >= 0.0f)) {
        Fail("{}: Adam state group '{}' has an invalid moment at index {} (m = {}, v = {})", source,
             s.group.name, k, s.m[k], s.v[k]);
      }
    }
  }
}

void Adam::Load(std::istream& in, const std::string& source) {
  HashingReader r(in, source, "Adam state");
  std::uint32_t version = 0;
  const AdamOptions options = ReadAdamHeader(r, source, &version);
  const auto count = r.Value<std::uint32_t>("the group count");
  if (count > kMaxGroups) {
    Fail("{}: Adam state claims {} parameter groups (more than {}: corrupt)", source, count,
         kMaxGroups);
  }
  std::vector<State> groups;
  groups.reserve(count);
  for (std::uint32_t i = 0; i < count; ++i) groups.push_back(ReadGroupState(r, i, groups, version));
  r.VerifyChecksum();
  // Values the checksum cannot vouch for (a state written from a broken optimiser).
  CheckLoadedValues(options, groups, source);

  // Commit: keep the buffers of groups that exist with the same name and size.
  for (State& s : groups) {
    for (const State& old : groups_) {
      if (old.group.name == s.group.name && old.group.size == s.group.size) {
        s.group.params = old.group.params;
        s.group.grads = old.group.grads;
      }
    }
  }
  options_ = options;
  groups_ = std::move(groups);
  decay1_ = detail::DecayPowers(options_.beta1);
  decay2_ = detail::DecayPowers(options_.beta2);
}

// ---- Helpers
// -------------------------------------------------------------------------------------

bool AllFinite(const float* values, std::size_t size) {
  if (size <= static_cast<std::size_t>(kGrain)) return ChunkFinite(values, size);
  std::atomic<bool> finite{true};
  ParallelForChunks(static_cast<std::int64_t>(size), 1 << 16,
                    [&](std::int64_t begin, std::int64_t end) {
                      if (!finite.load(std::memory_order_relaxed)) return;
                      if (!ChunkFinite(values + begin, static_cast<std::size_t>(end - begin))) {
                        finite.store(false, std::memory_order_relaxed);
                      }
                    });
  return finite.load();
}

}  // namespace hdr4d::method

#endif  // HWY_ONCE
