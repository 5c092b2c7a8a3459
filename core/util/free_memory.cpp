#include "core/util/free_memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hdr4d {

void ReturnFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

std::size_t ResidentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return 0;
  const long page = sysconf(_SC_PAGESIZE);
  return page > 0 ? pages_resident * static_cast<std::size_t>(page) : 0;
}

std::size_t PeakResidentBytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0 || usage.ru_maxrss <= 0) return 0;
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

std::size_t PhysicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(page)
                               : 0;
}

namespace {

// A "Key: N kB" line of a /proc file, in bytes; 0 when absent.
std::size_t ProcKilobytes(const char* file, const std::string& key) {
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream words(line.substr(key.size() + 1));
    std::size_t kb = 0;
    words >> kb;
    return kb * 1024;
  }
  return 0;
}

// A number in a one-line cgroup file; nullopt for "max", a missing file or no number.
std::optional<std::size_t> CgroupNumber(const std::string& file) {
  std::ifstream in(file);
  std::string word;
  if (!(in >> word) || word == "max") return std::nullopt;
  try {
    return static_cast<std::size_t>(std::stoull(word));
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

std::size_t AvailableMemoryBytes() {
  std::size_t available = ProcKilobytes("/proc/meminfo", "MemAvailable");
  const auto least = [&available](std::size_t bytes) {
    available = available == 0 ? bytes : std::min(available, bytes);
  };
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    const std::size_t mapped = ProcKilobytes("/proc/self/status", "VmSize");
    least(limit.rlim_cur > mapped ? limit.rlim_cur - mapped : 1);
  }
  const auto max = CgroupNumber("/sys/fs/cgroup/memory.max");
  const auto current = CgroupNumber("/sys/fs/cgroup/memory.current");
  if (max && current) least(*max > *current ? *max - *current : 1);
  return available;
}

}  // namespace hdr4d
