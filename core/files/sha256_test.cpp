#include "core/files/sha256.h"

#include <gtest/gtest.h>

#include <string>

#include "tests/testing.h"

namespace hdr4d {
namespace {

TEST(Sha256, KnownVectors) {
  // FIPS 180-4 examples: empty, one block, two blocks (56 bytes forces a second padding block).
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, FileMatchesBytesAcrossChunkBoundaries) {
  testing::TempDir dir;
  std::string data;
  for (int i = 0; i < 200000; ++i) data.push_back(static_cast<char>(i * 31 + 7));
  testing::WriteTextFile(dir / "blob.bin", data);
  EXPECT_EQ(Sha256File(dir / "blob.bin"), Sha256Hex(data));
  // A million 'a' (the FIPS long-message vector).
  testing::WriteTextFile(dir / "a.txt", std::string(1000000, 'a'));
  EXPECT_EQ(Sha256File(dir / "a.txt"),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, MissingFileNamesIt) {
  testing::TempDir dir;
  const std::string error = testing::ErrorOf([&] { Sha256File(dir / "nope.bin"); });
  EXPECT_NE(error.find("nope.bin"), std::string::npos) << error;
}

}  // namespace
}  // namespace hdr4d
