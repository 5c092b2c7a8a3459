// The radiance bank of the Dynamic Tone Mapper: one row per distinct normalised timestamp of the
// scene (F rows of mean log-HDR RGB), zero until written. Each render writes its time's row
// with the plain mean over all Gaussians; the context learner reads a window of rows before it.
// Follows the reference code (ARCHITECTURE §4, "Radiance bank").
//
// Rows no training view writes: on a monocular scene the held-out frames have timestamps of
// their own, so their rows are never written (our renders of held-out views do not write the
// bank). Left at zero (UnseenRows::kZero, the behaviour before, kept by --reference), every
// window holds zeros at the held-out positions, and a held-out time's own window has them at
// offsets no training time's window has: its context is one the learner never saw in training.
// UnseenRows::kInterpolate reads such a row as the linear interpolation in time of the nearest
// written rows (the nearest one past either end), the same way in training and rendering.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace hdr4d::method {

// How Window() reads a row that no render has written.
enum class UnseenRows { kZero, kInterpolate };

class RadianceBank {
 public:
  static constexpr int kColumns = 3;

  explicit RadianceBank(int num_times);  // num_times >= 1

  int size() const { return num_times_; }
  const std::vector<float>& rows() const { return rows_; }  // size() x 3, row-major
  const float* row(int index) const;
  bool written(int index) const;
  const std::vector<std::uint8_t>& written_rows() const { return written_; }

  // Sets row `index` to `mean3` and marks it written. A non-finite mean (a diverged render)
  // leaves the row as it was, so one bad render cannot poison every later context. Returns
  // whether it wrote.
  bool Write(int index, const float* mean3);

  // The rows the context learner reads for `index` with window k, oldest first, as the
  // reference slices them: index >= k: the k rows before index (excluding it); index 0: row 0
  // itself; 0 < index < k: rows 0 .. index-1 (shorter, unpadded).
  static int WindowBegin(int index, int k);
  static int WindowLength(int index, int k);
  // The window's rows (WindowLength x 3) copied to `out`; unwritten rows as `unseen` says.
  void Window(int index, int k, float* out, UnseenRows unseen = UnseenRows::kZero) const;
  std::vector<float> Window(int index, int k, UnseenRows unseen = UnseenRows::kZero) const;

  // Row of normalised time t in [0, 1]: int(t * F), F - 1 when t >= 1, clamped to [0, F-1]
  // (NaN -> 0).
  static int TimeIndex(double t_normalised, int num_times);

  // Binary, versioned, checksummed: "HDR4DBNK" | u32 version | u32 rows | f32 rows x 3 |
  // u8 written x rows (version 2) | u64 FNV-1a of the bytes after the version. Load requires the
  // same row count, reads version 1 (no written flags: a row is written where it is not all
  // zero, WrittenWhereNonZero), rejects truncated, corrupt or non-finite data with hdr4d::Error
  // naming `source`, and leaves the bank unchanged.
  void Save(std::ostream& out) const;
  void Load(std::istream& in, const std::string& source);

  // Replaces every row (size() x 3 finite values; checked) and the written flags (size() of 0
  // or 1; checked).
  void SetRows(const std::vector<float>& rows, const std::vector<std::uint8_t>& written);
  // The flags a bank saved without them implies: a row is written where it is not all zero
  // (an exact zero mean log-HDR in all three channels does not happen in practice).
  static std::vector<std::uint8_t> WrittenWhereNonZero(const std::vector<float>& rows);

 private:
  // Row `index` as kInterpolate reads it into out3 (unchanged when no row is written).
  void Interpolated(int index, float* out3) const;

  int num_times_;
  std::vector<float> rows_;
  std::vector<std::uint8_t> written_;  // 1 where a render wrote the row
};

}  // namespace hdr4d::method
