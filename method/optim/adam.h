// Adam as PyTorch's torch.optim.Adam computes it (no weight decay, no amsgrad), over named
// parameter groups with one learning rate each (ARCHITECTURE §4 "Optimisation"):
//   step += 1
//   m = m + (1 - beta1) (g - m)                      (torch: exp_avg.lerp_(grad, 1 - beta1))
//   v = beta2 v + (1 - beta2) g^2
//   p = p - (lr / (1 - beta1^step)) m / (sqrt(v) / sqrt(1 - beta2^step) + eps)
// The first step therefore moves every parameter by lr g / (|g| + eps), about lr sign(g).
// The bias corrections are formed in double, the per-element arithmetic in float, as torch does
// for float tensors (SIMD, with fused multiply-adds where the CPU has them: the last bit can
// differ between machines, never between runs or thread counts). Vectors of elements with
// g = m = v = 0 are skipped, which is exact (such an update changes nothing). Elements are
// updated in parallel; each is independent.
//
// The step count is kept per group, as torch keeps `step` per parameter tensor: the 3DGS
// densification surgery (cat / prune / opacity reset) keeps it and edits only the moments.
//
// Buffers: a group points at caller-owned parameter and gradient arrays. Any operation that
// changes a group's size (ResizeGroup, GatherGroup, AppendRows, Load) unbinds it; the caller
// applies the same change to its arrays and calls SetBuffers before the next Step.
//
// Non-finite gradients: a NaN would spread into the moments and from there into every later
// step, so the update leaves every vector of elements whose gradient holds a NaN or an infinity
// as it was, and AdamRowStep reports the group. The trainer checks the gradients (in the fused
// row step, or FirstNonFiniteGradient before Step) and stops with an error naming the group.
//
// Fused row steps: the gradients of a 4DGS model (~160 floats per Gaussian, 13 MB at 20k
// Gaussians) do not stay in cache between the backward that writes them and the step that reads
// them, and the update is memory-bound. BeginRowStep counts one step of the named groups, whose
// arrays hold `rows` rows of equal width; the backward then calls StepRows on each block of rows
// as soon as their gradients are final, while they are still in cache. The values are exactly
// those of StepGroup (each element's update is independent of the others).
//
// Visible rows (SetVisibleRows, `hdr4d train --visible-adam`; issue 55): a row step skips every
// row whose gradient is zero in that group (a Gaussian the view did not see) without reading
// its moments or parameters, and remembers the step its moments were last brought to. When the
// row has a gradient again, k steps later, its moments are first decayed as the k zero-gradient
// steps of dense Adam would have decayed them, exactly up to rounding (m *= beta1^k,
// v *= beta2^k), then stepped. This is NOT dense Adam: dense Adam also moves the parameter on
// each of those k steps along its decaying momentum (by step_size m / (sqrt(v) + eps)); that
// drift is skipped. Every operation that reads or reorders whole groups (Step, the surgery,
// turning the mode off) first catches every row up; a checkpoint saves each row's step.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hdr4d {
class HashingReader;  // core/files/binary_stream.h
}  // namespace hdr4d

namespace hdr4d::method {

struct AdamOptions {
  double beta1 = 0.9;
  double beta2 = 0.999;
  double eps = 1e-15;  // the 3DGS / 4DGS value (torch's default is 1e-8)

  // "" when valid, else a message naming the bad field: betas in [0, 1), eps > 0, all finite.
  std::string Validate() const;
};

// One named parameter group: `size` floats of parameters updated from `size` floats of
// gradients with learning rate `lr`. The arrays belong to the caller. `grads` may be null for a
// group whose gradient rows are only ever passed to AdamRowStep::StepRows (a whole-group Step of
// it is then an internal error).
struct AdamGroup {
  std::string name;
  float* params = nullptr;
  const float* grads = nullptr;
  std::size_t size = 0;
  float lr = 0.0f;
};

namespace detail {
// The per-step constants of one group's update.
struct StepConstants {
  float w1;  // 1 - beta1
  float beta2;
  float w2;              // 1 - beta2
  float inv_bias2_sqrt;  // 1 / sqrt(1 - beta2^step)
  float eps;
  float step_size;  // lr / (1 - beta1^step)
};
// The element update of Adam (the kernel Step uses) on n elements; false when a gradient held a
// NaN or an infinity (those vectors are left as they were).
bool AdamUpdate(float* p, const float* g, float* m, float* v, std::size_t n,
                const StepConstants& c);
// beta^k as float (computed in double): a table for small k, pow beyond it.
class DecayPowers {
 public:
  explicit DecayPowers(double beta = 0.0);
  float operator()(std::int64_t k) const;

 private:
  double beta_;
  std::vector<float> table_;
};
}  // namespace detail

// One step of some groups, applied block of rows by block of rows (Adam::BeginRowStep). The Adam
// it came from must not be resized or rebound until every row has been stepped.
class AdamRowStep {
 public:
  // Updates rows [begin, end) of every group of the step. Safe from several threads at once on
  // disjoint ranges; every row must be stepped exactly once. When grad_rows is given (one entry
  // per group, in the order of BeginRowStep), a non-null grad_rows[k] holds group k's gradient
  // of these rows (row `begin` first) in place of its bound gradient buffer.
  void StepRows(std::int64_t begin, std::int64_t end, std::span<const float* const> grad_rows = {});
  // From now on steps only the first `columns` floats of each row of `group` (no-op for a group
  // not in the step or columns >= its width). The caller guarantees that every other column has
  // a zero gradient and zero moments, i.e. has never had a gradient: Adam's update of such a
  // value is exactly nothing (m and v stay 0 and the parameter moves by 0), so skipping it
  // changes no bit. (The colour coefficients above the active degrees, most of each colour row
  // in a run's first thousands of iterations.)
  void LimitColumns(const std::string& group, std::size_t columns);
  // The first group (in the order given to BeginRowStep) whose gradient held a NaN or an
  // infinity in the rows stepped so far, or "". Such a group is partly stepped: its state must
  // be discarded (the trainer stops and keeps its last checkpoint).
  std::string FirstNonFinite() const;

 private:
  friend class Adam;
  struct Part {
    std::string name;
    float* params;
    const float* grads;
    float* m;
    float* v;
    std::size_t width;    // floats per row
    std::size_t columns;  // the first floats of each row that are stepped (LimitColumns)
    detail::StepConstants constants;
    // Visible rows: the step each row's moments were last brought to (null: dense), this
    // step's count and the decay powers.
    std::int64_t* seen = nullptr;
    std::int64_t step = 0;
    const detail::DecayPowers* decay1 = nullptr;
    const detail::DecayPowers* decay2 = nullptr;
  };
  // A visible-rows part's rows [begin, end) with gradient rows `g` (row `begin` first).
  static bool StepVisibleRows(const Part& part, std::int64_t begin, std::int64_t end,
                              const float* g);
  std::vector<Part> parts_;
  std::size_t rows_ = 0;
  std::unique_ptr<std::atomic<bool>[]> bad_;
};

class Adam {
 public:
  // Throws hdr4d::Error when the options are invalid.
  explicit Adam(const AdamOptions& options = {});

  const AdamOptions& options() const { return options_; }

  // Registers a group with zero moments and step 0. The name must be new and non-empty, and the
  // buffers non-null unless size is 0 (checked: a caller bug).
  void AddGroup(const AdamGroup& group);
  bool HasGroup(const std::string& name) const;
  std::vector<std::string> GroupNames() const;  // in the order they were added
  // The group's current binding, size and learning rate. The name must exist (checked).
  const AdamGroup& group(const std::string& name) const;

  // Points the group at (possibly reallocated) arrays; `size` must equal its size (checked).
  void SetBuffers(const std::string& name, float* params, const float* grads, std::size_t size);
  void SetLearningRate(const std::string& name, float lr);
  float LearningRate(const std::string& name) const;
  std::int64_t StepCount(const std::string& name) const;

  // One Adam update of every group (in the order added), or of one group. Every group stepped
  // must be bound to buffers of its size (checked).
  void Step();
  void StepGroup(const std::string& name);
  // Counts one step of each named group (bound, size a multiple of `rows`; checked) and returns
  // the row-wise update that applies it (see "Fused row steps" above).
  AdamRowStep BeginRowStep(const std::vector<std::string>& names, std::size_t rows);

  // Visible rows (see the top of this file): on for the row steps begun from now on. Turning it
  // off catches every row up.
  void SetVisibleRows(bool on);
  bool visible_rows() const { return visible_rows_; }
  // Brings every row's moments to its group's step (a no-op for rows already there).
  void CatchUpAll();
  // The step row `row` of the group was last brought to (its group's step unless visible rows
  // skipped it since).
  std::int64_t RowStep(const std::string& name, std::size_t row) const;

  // The moments, for diagnostics and tests (with visible rows: as of each row's RowStep).
  const std::vector<float>& FirstMoment(const std::string& name) const;
  const std::vector<float>& SecondMoment(const std::string& name) const;

  // ---- Surgery for densification (each keeps the step count; size changes unbind) ----------
  // Truncates, or extends with zero moments.
  void ResizeGroup(const std::string& name, std::size_t new_size);
  // Keeps the rows `keep` (in that order; each row is `row_width` floats). The group size must
  // be a multiple of row_width and every index a valid row (checked).
  void GatherGroup(const std::string& name,
                   const std::vector<std::uint32_t>& keep,
                   std::size_t row_width);
  // Appends `count` rows of `row_width` floats with zero moments.
  void AppendRows(const std::string& name, std::size_t count, std::size_t row_width);
  // Capacity for `size` floats of moments, so that growing up to it never reallocates (a
  // reallocation holds the old and the new moments at once). Untouched capacity costs address
  // space only. Keeps the binding.
  void ReserveGroup(const std::string& name, std::size_t size);
  // Reorders the rows in place (new row k is old row order[k]; `order` a permutation of the
  // group's rows, checked), as the caller reorders the parameters (time_order.h). Keeps the
  // binding and the step count.
  void PermuteRows(const std::string& name,
                   const std::vector<std::uint32_t>& order,
                   std::size_t row_width);
  // Zeroes the moments of the whole group (as 3DGS's opacity reset does), or of the given rows.
  void ResetMoments(const std::string& name);
  void ResetMoments(const std::string& name,
                    const std::vector<std::uint32_t>& rows,
                    std::size_t row_width);

  // The first group (in the order added; of `only` when given) whose bound gradients contain a
  // NaN or an infinity, or "" when all are finite.
  std::string FirstNonFiniteGradient() const;
  std::string FirstNonFiniteGradient(const std::vector<std::string>& only) const;

  // ---- Checkpoints ---------------------------------------------------------------------------
  // Binary state: options, and per group its name, size, step, learning rate and moments, with
  // a version and a checksum. Format (little-endian):
  //   "HDR4DADM" | u32 version (1) | f64 beta1, beta2, eps | u32 group count |
  //   per group: u32 name length, name bytes, u64 size, i64 step, f32 lr, f32 m[size],
  //   f32 v[size] | u64 FNV-1a (64-bit) of every byte after the version field.
  // Version 2 (written only when a row lags its group's step, i.e. with visible rows) adds after
  // each group's v: u64 row count (0: every row at the group's step), i64 row step[count].
  // Version 1 is written otherwise, byte for byte as before.
  void Save(std::ostream& out) const;
  // The number of bytes Save writes, without writing them: a checkpoint streams the state into
  // its file behind this length instead of building it in memory first (1.3 KB per Gaussian).
  std::uint64_t SavedSize() const;
  // Replaces the whole state (options included) with the stream's, or throws hdr4d::Error naming
  // `source` and what is wrong (bad magic, unsupported version, truncation, checksum, invalid
  // values) and leaves the optimiser unchanged. A loaded group keeps its current buffers when one
  // of the same name and size was bound before; otherwise it is unbound until SetBuffers.
  void Load(std::istream& in, const std::string& source);

 private:
  struct State {
    AdamGroup group;
    std::vector<float> m, v;
    std::int64_t step = 0;
    // Visible rows: the step each row's moments were last brought to; empty: all at `step`.
    std::vector<std::int64_t> seen;
  };
  // Brings the group's rows to its step and empties `seen`.
  void CatchUp(State& state) const;
  State& Find(const std::string& name);
  const State& Find(const std::string& name) const;
  // Load's parts: group `index`'s record (its name checked against the groups `before` it), and
  // the values the checksum cannot vouch for.
  static State ReadGroupState(HashingReader& r,
                              std::uint32_t index,
                              const std::vector<State>& before,
                              std::uint32_t version);
  bool AnyRowBehind() const;
  static void CheckLoadedValues(const AdamOptions& options,
                                const std::vector<State>& groups,
                                const std::string& source);
  void StepState(State& state);
  // Counts a step of the group and returns its update constants.
  detail::StepConstants NextStep(State& state);

  AdamOptions options_;
  std::vector<State> groups_;
  bool visible_rows_ = false;
  detail::DecayPowers decay1_, decay2_;  // beta1^k, beta2^k
};

// True when every value is finite (no NaN, no +-infinity); true for size 0.
bool AllFinite(const float* values, std::size_t size);

}  // namespace hdr4d::method
