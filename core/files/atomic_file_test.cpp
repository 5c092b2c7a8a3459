#include "core/files/atomic_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using testing::ReadTextFile;
using testing::TempDir;

std::vector<std::string> Names(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(AtomicFile, ReplacesARegularFileKeepingItsMode) {
  TempDir dir;
  testing::WriteTextFile(dir / "a.json", "old");
  fs::permissions(dir / "a.json", fs::perms(0640));
  WriteTextFileAtomic(dir / "a.json", "new");
  EXPECT_EQ(ReadTextFile(dir / "a.json"), "new");
  EXPECT_EQ(fs::status(dir / "a.json").permissions(), fs::perms(0640));
  EXPECT_EQ(Names(dir.path()), std::vector<std::string>{"a.json"});  // no temporary file left
}

// Issue 11, case 3: a symlink used to be replaced by a regular file.
TEST(AtomicFile, WritesThroughASymlinkToItsTarget) {
  TempDir dir;
  fs::create_directories(dir / "real");
  testing::WriteTextFile(dir / "real" / "target.json", "old");
  fs::create_symlink("real/target.json", dir / "link.json");
  WriteTextFileAtomic(dir / "link.json", "new");
  EXPECT_TRUE(fs::is_symlink(dir / "link.json"));
  EXPECT_EQ(ReadTextFile(dir / "real" / "target.json"), "new");
  // A dangling link: the file is created where it points.
  fs::create_symlink("real/later.json", dir / "dangling.json");
  WriteTextFileAtomic(dir / "dangling.json", "made");
  EXPECT_TRUE(fs::is_symlink(dir / "dangling.json"));
  EXPECT_EQ(ReadTextFile(dir / "real" / "later.json"), "made");
  // Images too: the image writer goes through the same routine.
  WriteImage(dir / "real" / "i.png", Image(2, 2, 3, Encoding::kSrgb, 0.5f));
  fs::create_symlink("real/i.png", dir / "i.png");
  WriteImage(dir / "i.png", Image(3, 3, 3, Encoding::kSrgb, 0.5f));
  EXPECT_TRUE(fs::is_symlink(dir / "i.png"));
  EXPECT_EQ(ReadImageSpec(dir / "real" / "i.png").width, 3);
}

// Issue 11, case 3: as root, `eval ... --out /dev/null` replaced the device node with a regular
// file. A private device node (mknod, root only) and a FIFO stand in for /dev/null here, so a
// regression breaks nothing outside the test's folder.
TEST(AtomicFile, WritesIntoSpecialFilesInsteadOfReplacingThem) {
  TempDir dir;
  const fs::path fifo = dir / "pipe.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] {
    std::ifstream in(fifo, std::ios::binary);
    received.assign(std::istreambuf_iterator<char>(in), {});
  });
  WriteTextFileAtomic(fifo, "through the pipe");
  reader.join();
  EXPECT_EQ(received, "through the pipe");
  EXPECT_TRUE(fs::is_fifo(fifo));

  const fs::path null = dir / "null";
  if (::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0)
    GTEST_SKIP() << "mknod needs root; the FIFO case above ran";
  WriteTextFileAtomic(null, "discarded");
  EXPECT_TRUE(fs::is_character_file(null));
  EXPECT_EQ(Names(dir.path()), (std::vector<std::string>{"null", "pipe.json"}));
}

TEST(AtomicFile, AFolderIsNotAFile) {
  TempDir dir;
  fs::create_directories(dir / "x.json");
  const std::string error = testing::ErrorOf([&] { WriteTextFileAtomic(dir / "x.json", "{}"); });
  EXPECT_NE(error.find("x.json: is a folder"), std::string::npos) << error;
}

TEST(AtomicFile, AFailingWriterLeavesTheOldFileAndNoTemporary) {
  TempDir dir;
  testing::WriteTextFile(dir / "keep.txt", "before");
  EXPECT_THROW(WriteFileAtomic(dir / "keep.txt",
                               [](std::ostream& out) {
                                 out << "half";
                                 Fail("the writer gave up");
                               }),
               Error);
  EXPECT_EQ(ReadTextFile(dir / "keep.txt"), "before");
  EXPECT_EQ(Names(dir.path()), std::vector<std::string>{"keep.txt"});
}

// What a killed writer leaves (its temporary file) is hidden and has no image or JSON
// extension, so nothing that lists a folder for images takes it for one.
TEST(AtomicFile, TemporaryFilesAreHiddenAndCarryNoExtensionOfTheTarget) {
  TempDir dir;
  fs::path seen;
  WriteFileAtomicAt(dir / "frame_0001.png", [&](const fs::path& tmp) {
    seen = tmp;
    testing::WriteTextFile(tmp, "x");
  });
  EXPECT_EQ(seen.parent_path(), dir.path());
  EXPECT_EQ(seen.filename().string().rfind(".frame_0001.png.tmp-", 0), 0u) << seen;
  EXPECT_NE(seen.extension(), ".png");
}

}  // namespace
}  // namespace hdr4d
