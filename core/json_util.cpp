#include "core/json_util.h"

#include <unistd.h>

#include <fstream>
#include <sstream>

#include "core/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

nlohmann::json ReadJsonFile(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) Fail("{}: file not found", path.string());
  std::ifstream file(path, std::ios::binary);
  if (!file) Fail("{}: cannot open for reading", path.string());
  std::stringstream buffer;
  buffer << file.rdbuf();
  try {
    return nlohmann::json::parse(buffer.str());
  } catch (const nlohmann::json::exception& e) {  // syntax, or a number out of range
    Fail("{}: invalid JSON: {}", path.string(), e.what());
  }
}

void WriteFileAtomic(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  std::error_code ec;
  if (path.has_parent_path()) {
    fs::create_directories(path.parent_path(), ec);
    if (ec) Fail("{}: cannot create folder: {}", path.string(), ec.message());
  }
  const fs::path tmp = path.string() + ".tmp" + std::to_string(getpid());
  {
    std::ofstream file(tmp, std::ios::binary | std::ios::trunc);
    if (!file) Fail("{}: cannot open for writing", path.string());
    try {
      write(file);
    } catch (...) {
      file.close();
      fs::remove(tmp, ec);
      throw;
    }
    file.flush();
    if (!file) {
      file.close();
      fs::remove(tmp, ec);
      Fail("{}: write failed (disk full?)", path.string());
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    Fail("{}: cannot move the written file into place: {}", path.string(), ec.message());
  }
}

void WriteTextFileAtomic(const fs::path& path, const std::string& text) {
  WriteFileAtomic(path, [&](std::ostream& out) { out << text; });
}

void WriteJsonFile(const fs::path& path, const nlohmann::json& value) {
  WriteTextFileAtomic(path, value.dump(1) + "\n");
}

}  // namespace hdr4d
