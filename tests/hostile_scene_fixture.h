// The set-up both hostile-user suites start from (issues 11 and 51): S = a small demo scene with
// its LDR images, R = a short run on it, both in a fresh temporary folder.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/testing.h"

namespace hdr4d {

class HostileScene : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = testing::RunHdr4d("make-demo-scene --out " + S() +
                               " --cameras 4 --size 32 --timestamps 4 --spp 1");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = testing::RunHdr4d("synth-ldr --data " + S());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  void TrainRun() {
    const auto r = testing::RunHdr4d("train --data " + S() + " --out " + R() +
                                     " --iterations 20 --threads 1");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::string S() const { return (dir_ / "S").string(); }
  std::string R() const { return (dir_ / "R").string(); }
  std::filesystem::path operator/(const std::string& name) const { return dir_ / name; }

  testing::TempDir dir_;
};

// A refused command: exit 1 and `part` in what it said. `dataset check` reports its problems on
// stdout (it is the command's report), the others on stderr; either way the problem is named.
inline void ExpectRefused(const testing::CommandResult& r, const std::string& args,
                          const std::string& part) {
  const std::string said = r.err + r.out;
  EXPECT_EQ(r.exit_code, 1) << args << "\n" << said;
  EXPECT_NE(said.find(part), std::string::npos) << args << "\nmissing: " << part << "\n" << said;
}

}  // namespace hdr4d
