// Length-prefixed arrays in the HexPlane checkpoints (hexplane_model_io.cpp, the trainer's state
// in hexplane_train_state.cpp): a value count before the values, so a truncated or foreign file
// is refused with its name instead of read as garbage.
#pragma once

#include <cstdint>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "core/util/error.h"

namespace hdr4d::baselines::hexplane {

template <typename V>
void WriteArray(std::ostream& out, const std::vector<V>& v) {
  const std::uint64_t n = v.size();
  out.write(reinterpret_cast<const char*>(&n), sizeof n);
  out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(n * sizeof(V)));
}

// `expected`: the count the configuration gives.
template <typename V>
void ReadArray(std::istream& in, std::size_t expected, const std::string& file, const char* what,
               std::vector<V>* v) {
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  if (!in || n != expected)
    Fail("{}: {} has {} values where the configuration gives {} (or the file is cut short)", file,
         what, n, expected);
  v->resize(n);
  in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(V)));
  if (!in) Fail("{}: cut short in {}", file, what);
}

// An array whose length the file gives (at most `max_values`).
template <typename V>
void ReadArrayOfAnyLength(std::istream& in, std::uint64_t max_values, const std::string& file,
                          const char* what, std::vector<V>* v) {
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  if (!in || n > max_values) Fail("{}: bad length {} of {} (or the file is cut short)", file, n, what);
  v->resize(n);
  in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(V)));
  if (!in) Fail("{}: cut short in {}", file, what);
}

template <typename V>
void WritePod(std::ostream& out, const V& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}

template <typename V>
V ReadPod(std::istream& in, const std::string& file, const char* what) {
  V v{};
  in.read(reinterpret_cast<char*>(&v), sizeof v);
  if (!in) Fail("{}: cut short in {}", file, what);
  return v;
}

}  // namespace hdr4d::baselines::hexplane
