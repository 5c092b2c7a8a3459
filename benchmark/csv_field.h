// One CSV field as RFC 4180 writes it: quoted (with its quotes doubled) only when it holds a
// comma, a quote or a newline. The tables' and bench compare's CSV files share it.
#pragma once

#include <string>

namespace hdr4d::bench {

inline std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q.push_back('"');
    q.push_back(c);
  }
  q.push_back('"');
  return q;
}

}  // namespace hdr4d::bench
