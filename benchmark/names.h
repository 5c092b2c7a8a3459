// Names are names: a suite's name and its scene, method, variant, table and group names, and the
// labels of collected or submitted runs, become parts of paths (a table's file, a report's
// images, a run's folder) and of generated scripts. A name with a '/' or a '\', "." or "..", a
// control character, or more than 200 bytes wrote outside --out (issue 51, case 9), so every
// reader of a name calls one check.
#pragma once

#include <string>

namespace hdr4d::bench {

inline constexpr std::size_t kMaxNameBytes = 200;

// The problem with `name` as a name ("" when it is one).
std::string NameProblem(const std::string& name);
// Throws hdr4d::Error "<where>: <problem>" when `name` is not a name; `where` names the file
// and the key (e.g. "suite.json.tables[0].id").
void RequireName(const std::string& name, const std::string& where);

}  // namespace hdr4d::bench
