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
constexpr std::uint32_t kBankVersion = 1;

}  // namespace

RadianceBank::RadianceBank(int num_times)
    : num_times_(num_times), rows_(std::size_t(std::max(num_times, 0)) * kColumns, 0.0f) {
  HDR4D_CHECK(num_times >= 1);
}

const float* RadianceBank::row(int index) const {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  return rows_.data() + std::size_t(index) * kColumns;
}

bool RadianceBank::Write(int index, const float* mean3) {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  for (int c = 0; c < kColumns; ++c) {
    if (!std::isfinite(mean3[c])) return false;
  }
  std::copy(mean3, mean3 + kColumns, rows_.begin() + std::size_t(index) * kColumns);
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

void RadianceBank::Window(int index, int k, float* out) const {
  HDR4D_CHECK(index >= 0 && index < num_times_);
  const int begin = WindowBegin(index, k), length = WindowLength(index, k);
  std::copy(rows_.begin() + std::size_t(begin) * kColumns,
            rows_.begin() + std::size_t(begin + length) * kColumns, out);
}

std::vector<float> RadianceBank::Window(int index, int k) const {
  std::vector<float> out(std::size_t(WindowLength(index, k)) * kColumns);
  Window(index, k, out.data());
  return out;
}

int RadianceBank::TimeIndex(double t_normalised, int num_times) {
  HDR4D_CHECK(num_times >= 1);
  if (!(t_normalised > 0.0)) return 0;  // also NaN
  if (t_normalised >= 1.0) return num_times - 1;
  const double row = std::floor(t_normalised * num_times);
  return static_cast<int>(std::min(row, double(num_times - 1)));
}

void RadianceBank::SetRows(const std::vector<float>& rows) {
  HDR4D_CHECK(rows.size() == rows_.size());
  for (float v : rows) HDR4D_CHECK(std::isfinite(v));
  rows_ = rows;
}

void RadianceBank::Save(std::ostream& out) const {
  HashingWriter w(out);
  w.Bytes(kBankMagic, sizeof(kBankMagic));
  w.Value(kBankVersion);
  w.ResetHash();
  w.Value(static_cast<std::uint32_t>(num_times_));
  w.Bytes(rows_.data(), rows_.size() * sizeof(float));
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
  if (version != kBankVersion) {
    Fail("{}: radiance bank version {} is not supported (this build reads version {})", source,
         version, kBankVersion);
  }
  r.ResetHash();
  const auto count = r.Value<std::uint32_t>("the row count");
  if (count != static_cast<std::uint32_t>(num_times_)) {
    Fail("{}: radiance bank has {} rows, this scene has {} timestamps", source, count, num_times_);
  }
  std::vector<float> rows = r.Floats(std::uint64_t(count) * kColumns, "the rows");
  r.VerifyChecksum();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!std::isfinite(rows[i])) {
      Fail("{}: radiance bank row {} has a non-finite value", source, i / kColumns);
    }
  }
  rows_ = std::move(rows);
}

}  // namespace hdr4d::method
