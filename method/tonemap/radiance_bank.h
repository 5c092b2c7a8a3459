// The radiance bank of the Dynamic Tone Mapper: one row per distinct normalised timestamp of the
// scene (F rows of mean log-HDR RGB), zero until written. Each render writes its time's row
// with the plain mean over all Gaussians; the context learner reads a window of rows before it.
// Follows the reference code (ARCHITECTURE §4, "Radiance bank").
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace hdr4d::method {

class RadianceBank {
 public:
  static constexpr int kColumns = 3;

  explicit RadianceBank(int num_times);  // num_times >= 1

  int size() const { return num_times_; }
  const std::vector<float>& rows() const { return rows_; }  // size() x 3, row-major
  const float* row(int index) const;

  // Sets row `index` to `mean3`. A non-finite mean (a diverged render) leaves the row as it was,
  // so one bad render cannot poison every later context. Returns whether it wrote.
  bool Write(int index, const float* mean3);

  // The rows the context learner reads for `index` with window k, oldest first, as the
  // reference slices them: index >= k: the k rows before index (excluding it); index 0: row 0
  // itself; 0 < index < k: rows 0 .. index-1 (shorter, unpadded).
  static int WindowBegin(int index, int k);
  static int WindowLength(int index, int k);
  // The window's rows (WindowLength x 3) copied to `out`.
  void Window(int index, int k, float* out) const;
  std::vector<float> Window(int index, int k) const;

  // Row of normalised time t in [0, 1]: int(t * F), F - 1 when t >= 1, clamped to [0, F-1]
  // (NaN -> 0).
  static int TimeIndex(double t_normalised, int num_times);

  // Binary, versioned, checksummed: "HDR4DBNK" | u32 version | u32 rows | f32 rows x 3 | u64
  // FNV-1a of the bytes after the version. Load requires the same row count, rejects truncated,
  // corrupt or non-finite data with hdr4d::Error naming `source`, and leaves the bank unchanged.
  void Save(std::ostream& out) const;
  void Load(std::istream& in, const std::string& source);

  // Replaces every row (size() x 3 finite values; checked).
  void SetRows(const std::vector<float>& rows);

 private:
  int num_times_;
  std::vector<float> rows_;
};

}  // namespace hdr4d::method
