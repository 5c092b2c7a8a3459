#include "method/tonemap/radiance_bank.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/files/binary_stream.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using testing::ErrorOf;

// Row i holds (i, 10 i, 100 i).
RadianceBank NumberedBank(int rows) {
  RadianceBank bank(rows);
  for (int i = 0; i < rows; ++i) {
    const float v[3] = {float(i), 10.0f * i, 100.0f * i};
    EXPECT_TRUE(bank.Write(i, v));
  }
  return bank;
}

std::vector<int> WindowRows(const RadianceBank& bank, int index, int k) {
  const std::vector<float> w = bank.Window(index, k);
  std::vector<int> ids;
  for (std::size_t r = 0; r < w.size() / 3; ++r) ids.push_back(int(w[r * 3]));
  return ids;
}

TEST(RadianceBank, StartsAtZeroAndWritesRows) {
  RadianceBank bank(4);
  EXPECT_EQ(bank.size(), 4);
  for (float v : bank.rows()) EXPECT_EQ(v, 0.0f);
  const float mean[3] = {0.5f, -1.0f, 2.0f};
  EXPECT_TRUE(bank.Write(2, mean));
  EXPECT_EQ(bank.row(2)[0], 0.5f);
  EXPECT_EQ(bank.row(2)[1], -1.0f);
  EXPECT_EQ(bank.row(2)[2], 2.0f);
  EXPECT_EQ(bank.row(1)[0], 0.0f);
}

TEST(RadianceBank, NonFiniteMeanLeavesTheRow) {
  RadianceBank bank(2);
  const float good[3] = {1, 2, 3};
  bank.Write(1, good);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const float bad1[3] = {nan, 0, 0}, bad2[3] = {0, 0, -inf};
  EXPECT_FALSE(bank.Write(1, bad1));
  EXPECT_FALSE(bank.Write(1, bad2));
  EXPECT_EQ(bank.row(1)[0], 1.0f);
  EXPECT_EQ(bank.row(1)[2], 3.0f);
}

TEST(RadianceBank, WindowSlicesAsTheReference) {
  const RadianceBank bank = NumberedBank(30);
  EXPECT_EQ(WindowRows(bank, 0, 20), std::vector<int>({0}));           // the row itself
  EXPECT_EQ(WindowRows(bank, 1, 20), std::vector<int>({0}));           // rows before it
  EXPECT_EQ(WindowRows(bank, 3, 20), std::vector<int>({0, 1, 2}));     // shorter, unpadded
  EXPECT_EQ(WindowRows(bank, 25, 3), std::vector<int>({22, 23, 24}));  // k rows, excluding it
  EXPECT_EQ(WindowRows(bank, 3, 3), std::vector<int>({0, 1, 2}));      // index == k
  const std::vector<int> w20 = WindowRows(bank, 29, 20);
  ASSERT_EQ(w20.size(), 20u);
  EXPECT_EQ(w20.front(), 9);
  EXPECT_EQ(w20.back(), 28);
  EXPECT_EQ(RadianceBank::WindowLength(0, 1), 1);
  EXPECT_EQ(RadianceBank::WindowLength(7, 1), 1);
  EXPECT_EQ(RadianceBank::WindowBegin(7, 1), 6);
  // The whole row, all three values.
  const std::vector<float> w = bank.Window(25, 1);
  EXPECT_EQ(w, std::vector<float>({24.0f, 240.0f, 2400.0f}));
}

TEST(RadianceBank, TimeIndexQuantisesNormalisedTime) {
  EXPECT_EQ(RadianceBank::TimeIndex(0.0, 4), 0);
  EXPECT_EQ(RadianceBank::TimeIndex(0.24, 4), 0);
  EXPECT_EQ(RadianceBank::TimeIndex(0.25, 4), 1);
  EXPECT_EQ(RadianceBank::TimeIndex(0.5, 4), 2);
  EXPECT_EQ(RadianceBank::TimeIndex(0.999999, 4), 3);
  EXPECT_EQ(RadianceBank::TimeIndex(1.0, 4), 3);  // t = 1: the last row
  EXPECT_EQ(RadianceBank::TimeIndex(1.5, 4), 3);
  EXPECT_EQ(RadianceBank::TimeIndex(-0.1, 4), 0);
  EXPECT_EQ(RadianceBank::TimeIndex(std::nan(""), 4), 0);
  EXPECT_EQ(RadianceBank::TimeIndex(0.7, 1), 0);
  EXPECT_EQ(RadianceBank::TimeIndex(1.0, 1), 0);
  // F uniform timestamps i / (F - 1), as a dataset normalises them, hit every row once.
  for (int f : {2, 5, 7, 30}) {
    std::vector<int> hits(f, 0);
    for (int i = 0; i < f; ++i) ++hits[RadianceBank::TimeIndex(double(i) / (f - 1), f)];
    EXPECT_EQ(hits, std::vector<int>(f, 1)) << f;
  }
}

// Rows `rows` of a bank of `size`, numbered as NumberedBank; the others never written.
RadianceBank BankWithRows(int size, const std::vector<int>& rows) {
  RadianceBank bank(size);
  for (int i : rows) {
    const float v[3] = {float(i), 10.0f * i, 100.0f * i};
    EXPECT_TRUE(bank.Write(i, v));
  }
  return bank;
}

std::vector<float> FirstColumn(const std::vector<float>& window) {
  std::vector<float> out;
  for (std::size_t r = 0; r < window.size() / 3; ++r) out.push_back(window[r * 3]);
  return out;
}

TEST(RadianceBank, UnwrittenRowsReadAsZerosOrInterpolatedInTime) {
  // A monocular scene's held-out frames: rows 2 and 6 never written, 3 between two of them.
  const RadianceBank bank = BankWithRows(9, {0, 1, 4, 5, 7, 8});
  EXPECT_FALSE(bank.written(2));
  EXPECT_TRUE(bank.written(4));
  EXPECT_EQ(FirstColumn(bank.Window(8, 8)), (std::vector<float>{0, 1, 0, 0, 4, 5, 0, 7}));
  const std::vector<float> w = bank.Window(8, 8, UnseenRows::kInterpolate);
  EXPECT_EQ(FirstColumn(w), (std::vector<float>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_FLOAT_EQ(w[2 * 3 + 1], 20.0f);  // every column interpolates
  EXPECT_FLOAT_EQ(w[3 * 3 + 2], 300.0f);
  // Past either end: the nearest written row.
  const RadianceBank ends = BankWithRows(6, {2, 3});
  EXPECT_EQ(FirstColumn(ends.Window(5, 5, UnseenRows::kInterpolate)),
            (std::vector<float>{2, 2, 2, 3, 3}));
  // Nothing written yet: zeros either way.
  EXPECT_EQ(RadianceBank(4).Window(3, 3, UnseenRows::kInterpolate), std::vector<float>(9, 0.0f));
  // A written row of zeros is a value, not a gap.
  RadianceBank zero = BankWithRows(3, {0, 2});
  const float z[3] = {0, 0, 0};
  zero.Write(2, z);
  EXPECT_EQ(FirstColumn(zero.Window(2, 2, UnseenRows::kInterpolate)), (std::vector<float>{0, 0}));
}

TEST(RadianceBank, SaveLoadRoundTrip) {
  RadianceBank bank = BankWithRows(6, {1, 2, 4});
  const float z[3] = {0, 0, 0};
  bank.Write(5, z);  // written, and zero
  std::stringstream s;
  bank.Save(s);
  RadianceBank loaded(6);
  loaded.Load(s, "bank.bin");
  EXPECT_EQ(loaded.rows(), bank.rows());
  EXPECT_EQ(loaded.written_rows(), bank.written_rows());
  EXPECT_TRUE(loaded.written(5));
  EXPECT_FALSE(loaded.written(3));
}

// A bank file written by hand, with a valid checksum: `version`, rows x 3 floats, then the
// written flags (version 2).
std::string HandWritten(std::uint32_t version, const std::vector<float>& rows,
                        const std::vector<std::uint8_t>& flags = {}) {
  std::stringstream s;
  HashingWriter w(s);
  w.Bytes("HDR4DBNK", 8);
  w.Value(version);
  w.ResetHash();
  w.Value(static_cast<std::uint32_t>(rows.size() / 3));
  w.Bytes(rows.data(), rows.size() * sizeof(float));
  w.Bytes(flags.data(), flags.size());
  w.Value(w.hash());
  return s.str();
}

TEST(RadianceBank, LoadsVersionOneWithRowsWrittenWhereNotZero) {
  RadianceBank bank(3);
  std::stringstream s(HandWritten(1, {1, 2, 3, 0, 0, 0, 0, -0.5f, 0}));
  bank.Load(s, "old.bin");
  EXPECT_EQ(bank.written_rows(), (std::vector<std::uint8_t>{1, 0, 1}));
}
std::string Saved(const RadianceBank& bank) {
  std::stringstream s;
  bank.Save(s);
  return s.str();
}

std::string LoadError(RadianceBank& bank, const std::string& bytes) {
  std::stringstream s(bytes);
  return ErrorOf([&] { bank.Load(s, "bank.bin"); });
}

TEST(RadianceBank, LoadRejectsBadDataAndKeepsTheBank) {
  const std::string good = Saved(NumberedBank(3));
  RadianceBank bank(3);
  const float keep[3] = {7, 8, 9};
  bank.Write(0, keep);
  const std::vector<float> before = bank.rows();

  for (std::size_t cut = 0; cut < good.size(); ++cut) {
    const std::string e = LoadError(bank, good.substr(0, cut));
    EXPECT_NE(e.find("bank.bin"), std::string::npos) << cut;
    EXPECT_NE(e.find("truncated"), std::string::npos) << cut << ": " << e;
  }
  std::string corrupt = good;
  corrupt[20] ^= 0x10;  // inside the rows
  EXPECT_NE(LoadError(bank, corrupt).find("checksum"), std::string::npos);
  std::string flag = good;
  flag[good.size() - 9] = 7;  // the last written flag, before the checksum
  EXPECT_NE(LoadError(bank, flag).find("checksum"), std::string::npos);
  std::string magic = good;
  magic[0] = 'X';
  EXPECT_NE(LoadError(bank, magic).find("bad magic"), std::string::npos);
  std::string version = good;
  version[8] = 9;
  EXPECT_NE(LoadError(bank, version).find("version 9"), std::string::npos);
  RadianceBank other(4);
  EXPECT_NE(LoadError(other, good).find("3 rows"), std::string::npos);

  // A non-finite row, and a flag that is neither 0 nor 1, with valid checksums.
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_NE(LoadError(bank, HandWritten(1, {0, 0, 0, 0, inf, 0, 0, 0, 0})).find("row 1 has a non-finite"),
            std::string::npos);
  EXPECT_NE(LoadError(bank, HandWritten(2, std::vector<float>(9, 0.0f), {1, 7, 0}))
                .find("row 1 has a bad written flag"),
            std::string::npos);

  EXPECT_EQ(bank.rows(), before);
  EXPECT_EQ(LoadError(bank, good), "");
  EXPECT_NE(bank.rows(), before);
}

}  // namespace
}  // namespace hdr4d::method
