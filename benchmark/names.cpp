#include "benchmark/names.h"

#include <fmt/format.h>

#include "core/util/error.h"

namespace hdr4d::bench {

std::string NameProblem(const std::string& name) {
  if (name.empty()) return "a name may not be empty";
  if (name == "." || name == "..")
    return fmt::format("'{}' is a path, not a name", name);
  if (name.size() > kMaxNameBytes)
    return fmt::format("a name has at most {} bytes, this one {}", kMaxNameBytes, name.size());
  for (const unsigned char c : name) {
    if (c == '/' || c == '\\')
      return fmt::format("'{}' has a '{}': names are names, not paths", name, static_cast<char>(c));
    if (c < 0x20 || c == 0x7f)
      return fmt::format("the name has a control character (0x{:02x})", static_cast<int>(c));
  }
  return "";
}

void RequireName(const std::string& name, const std::string& where) {
  if (const std::string problem = NameProblem(name); !problem.empty())
    Fail("{}: {}", where, problem);
}

}  // namespace hdr4d::bench
