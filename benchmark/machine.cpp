#include "benchmark/machine.h"

#include <sched.h>
#include <unistd.h>

#include <fstream>
#include <thread>

#include "benchmark/code_version_generated.h"
#include "method/raster/simd_dispatch.h"

namespace hdr4d::bench {

std::string CodeVersion() { return HDR4D_CODE_VERSION; }
std::string GitDescribe() { return HDR4D_GIT_DESCRIBE; }

int AvailableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

nlohmann::json MachineInfo() {
  std::string model = "unknown";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  double memory_gb = 0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string line; std::getline(meminfo, line);) {
    if (line.rfind("MemTotal:", 0) == 0) {
      memory_gb = std::stod(line.substr(9)) / (1024.0 * 1024.0);
      break;
    }
  }
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  // The target the method's kernels dispatch to (HDR4D_SIMD_TARGETS may limit it).
  const std::string simd = method::ActiveSimdTarget();
  return {{"cpu_model", model},
          {"cores", AvailableCores()},
          {"simd_target", simd},
          {"memory_gb", std::round(memory_gb * 10) / 10},
          {"hostname", host}};
}

}  // namespace hdr4d::bench
