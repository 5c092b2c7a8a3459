#include "tests/testing.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace hdr4d::testing {
namespace fs = std::filesystem;

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "hdr4d_test_XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ignored);
  fs::remove_all(path_, ignored);
}

fs::path SourceDir() { return fs::path(HDR4D_SOURCE_DIR); }

std::optional<fs::path> SharedData(const std::string& name) {
  for (const fs::path& root :
       {SourceDir() / ".." / "shared" / "data", SourceDir() / "shared" / "data"}) {
    if (fs::exists(root / name)) return fs::canonical(root / name);
  }
  return std::nullopt;
}

std::string Hdr4dBinary() { return HDR4D_BINARY_PATH; }

CommandResult RunHdr4d(const std::string& args) { return RunHdr4dWith("", args); }

CommandResult RunHdr4dWith(const std::string& prefix, const std::string& args) {
  static int counter = 0;
  const fs::path dir = fs::temp_directory_path();
  const std::string tag = std::to_string(getpid()) + "_" + std::to_string(counter++);
  const fs::path out = dir / ("hdr4d_cmd_out_" + tag), err = dir / ("hdr4d_cmd_err_" + tag);
  const std::string command = prefix + (prefix.empty() ? "" : " ") + "'" + HDR4D_BINARY_PATH +
                              "' " + args + " >'" + out.string() + "' 2>'" + err.string() +
                              "' </dev/null";
  const int status = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = ReadTextFile(out);
  result.err = ReadTextFile(err);
  fs::remove(out);
  fs::remove(err);
  return result;
}

Image RandomImage(
    int width, int height, int channels, unsigned seed, float lo, float hi, Encoding encoding) {
  Image image(width, height, channels, encoding);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(lo, hi);
  for (float& v : image.values()) v = dist(rng);
  return image;
}

void WriteTextFile(const fs::path& path, const std::string& text) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream file(path, std::ios::binary);
  file << text;
}

std::string ReadTextFile(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

}  // namespace hdr4d::testing
