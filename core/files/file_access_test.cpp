#include "core/files/file_access.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;

// Issue 51, case 13: /dev/zero as an image hung eval, dataset check and train at 100% CPU, and
// a FIFO blocks its reader forever. Such inputs are refused by name before they are opened.
TEST(FileAccess, DevicesFifosAndSocketsAreNotInputFiles) {
  testing::TempDir dir;
  EXPECT_EQ(InputFileProblem("/dev/zero"), "is a character device, not a regular file");
  const fs::path fifo = dir / "pipe.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(InputFileProblem(fifo), "is a FIFO (named pipe), not a regular file");
  const fs::path sock = dir / "s.png";
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", sock.c_str());
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  EXPECT_EQ(InputFileProblem(sock), "is a socket, not a regular file");
  ::close(fd);
  // Through a symlink too, and RequireInputFile names the path.
  fs::create_symlink("/dev/zero", dir / "zero.json");
  EXPECT_NE(testing::ErrorOf([&] { RequireInputFile(dir / "zero.json"); })
                .find("zero.json: is a character device"),
            std::string::npos);
  testing::WriteTextFile(dir / "ok.json", "{}");
  EXPECT_EQ(InputFileProblem(dir / "ok.json"), "");
}

}  // namespace
}  // namespace hdr4d
