#include "method/tonemap/radiance_bank.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <istream>
#include <ostream>

#include "core/util/error.h"
#include "core/files/binary_stream.h"

namespace hdr4d::method {
namespace {

constexpr char kBankMagic[8] = {'H', 'D', 'R', '4', 'D', 'B', 'N', 'K'};
constexpr std::uint32_t kBankVersion = 2;  // 2: written flags

}  // namespace

RadianceBank::RadianceBank(int num_times)
    : num_times_(num_times),
      rows_(std::size_t(std::max(num_times, 0)) * kColumns, 0.0f),
      written_(std::size_t(std::max(num_times, 0)), 0) {
  HDR4D_CHECK(num_times >= 1);
}

const float* RadianceBank::row(int index) const {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  return rows_.data() + std::size_t(index) * kColumns;
}

bool RadianceBank::written(int index) const {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  return written_[std::size_t(index)] != 0;
}

bool RadianceBank::Write(int index, const float* mean3) {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  for (int c = 0; c < kColumns; ++c) {
    if (!std::isfinite(mean3[c])) return false;
  }
  std::copy(mean3, mean3 + kColumns, rows_.begin() + std::size_t(index) * kColumns);
  written_[std::size_t(index)] = 1;
  return true;
}

int RadianceBank::WindowBegin(int index, int k) {
  HDR4D_CHECK(index >= 0 && k >= 1);
  return index >= k ? index - k : 0;
}

int RadianceBank::WindowLength(int index, int k) {
  HDR4D_CHECK(index >= 0 && k >= 1);
  if (index == 0) return 1;
  return std::min(index, k);
}

void RadianceBank::Window(int index, int k, float* out, UnseenRows unseen) const {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  const int begin = WindowBegin(index, k), length = WindowLength(index, k);
  std::copy(rows_.begin() + std::size_t(begin) * kColumns,
            rows_.begin() + std::size_t(begin + length) * kColumns, out);
  if (unseen != UnseenRows::kInterpolate) return;
  for (int j = 0; j < length; ++j) {
    if (!written_[std::size_t(begin + j)]) Interpolated(begin + j, out + std::size_t(j) * kColumns);
  }
}

std::vector<float> RadianceBank::Window(int index, int k, UnseenRows unseen) const {
  std::vector<float> out(std::size_t(WindowLength(index, k)) * kColumns);
  Window(index, k, out.data(), unseen);
  return out;
}

void RadianceBank::Interpolated(int index, float* out3) const {
  int lo = index - 1, hi = index + 1;
  while (lo >= 0 && !written_[std::size_t(lo)]) --lo;
  while (hi < num_times_ && !written_[std::size_t(hi)]) ++hi;
  const bool has_lo = lo >= 0, has_hi = hi < num_times_;
  if (!has_lo && !has_hi) return;  // nothing written yet: the zero row stays
  const float* a = has_lo ? row(lo) : row(hi);
  const float* b = has_hi ? row(hi) : row(lo);
  // Weight of b: the position between the two written rows (one of them alone past an end).
  const float w = has_lo && has_hi ? float(index - lo) / float(hi - lo) : 0.0f;
  for (int c = 0; c < kColumns; ++c) out3[c] = a[c] + w * (b[c] - a[c]);
}

int RadianceBank::TimeIndex(double t_normalised, int num_times) {
  HDR4D_CHECK(num_times >= 1);
  if (!(t_normalised > 0.0)) return 0;  // also NaN
  if (t_normalised >= 1.0) return num_times - 1;
  const double row = std::floor(t_normalised * num_times);
  return static_cast<int>(std::min(row, double(num_times - 1)));
}

void RadianceBank::SetRows(const std::vector<float>& rows, const std::vector<std::uint8_t>& written) {
  HDR4D_CHECK(rows.size() == rows_.size() && written.size() == written_.size());
  for (float v : rows) HDR4D_CHECK(std::isfinite(v));
  for (std::uint8_t f : written) HDR4D_CHECK(f <= 1);
  rows_ = rows;
  written_ = written;
}

std::vector<std::uint8_t> RadianceBank::WrittenWhereNonZero(const std::vector<float>& rows) {
  std::vector<std::uint8_t> written(rows.size() / kColumns, 0);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i] != 0.0f) written[i / kColumns] = 1;
  }
  return written;
}

void RadianceBank::Save(std::ostream& out) const {
  HashingWriter w(out);
  w.Bytes(kBankMagic, sizeof(kBankMagic));
  w.Value(kBankVersion);
  w.ResetHash();
  w.Value(static_cast<std::uint32_t>(num_times_));
  w.Bytes(rows_.data(), rows_.size() * sizeof(float));
  w.Bytes(written_.data(), written_.size());
  w.Value(w.hash());
}

void RadianceBank::Load(std::istream& in, const std::string& source) {
  HashingReader r(in, source, "radiance bank");
  char magic[sizeof(kBankMagic)];
  r.Bytes(magic, sizeof(magic), "the header");
  if (std::memcmp(magic, kBankMagic, sizeof(kBankMagic)) != 0) {
    Fail("{}: not a radiance bank (bad magic; expected \"HDR4DBNK\")", source);
  }
  const auto version = r.Value<std::uint32_t>("the version");
  if (version != 1 && version != kBankVersion) {
    Fail("{}: radiance bank version {} is not supported (this build reads versions 1 and {})",
         source, version, kBankVersion);
  }
  r.ResetHash();
  const auto count = r.Value<std::uint32_t>("the row count");
  if (count != static_cast<std::uint32_t>(num_times_)) {
    Fail("{}: radiance bank has {} rows, this scene has {} timestamps", source, count, num_times_);
  }
  std::vector<float> rows = r.Floats(std::uint64_t(count) * kColumns, "the rows");
  std::vector<std::uint8_t> written(count, 0);
  if (version >= 2) r.Bytes(written.data(), written.size(), "the written flags");
  r.VerifyChecksum();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!std::isfinite(rows[i])) {
      Fail("{}: radiance bank row {} has a non-finite value", source, i / kColumns);
    }
  }
  for (std::size_t i = 0; i < written.size(); ++i) {
    if (written[i] > 1) Fail("{}: radiance bank row {} has a bad written flag ({})", source, i, written[i]);
  }
  if (version == 1) written = WrittenWhereNonZero(rows);
  rows_ = std::move(rows);
  written_ = std::move(written);
}

}  // namespace hdr4d::method
