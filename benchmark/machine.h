// Where and with what a run was made: the code version of the result-producing sources and the
// machine (CPU model, cores, SIMD target the kernels dispatch to).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace hdr4d::bench {

// Hash of the committed trees and uncommitted changes of the sources that produce results
// (core, method, baselines, datagen, the train/render/tone-curves commands, the harness's
// scoring), fixed at build time; "unversioned" outside a git checkout.
std::string CodeVersion();
// `git describe --always --dirty` at build time.
std::string GitDescribe();

// {"cpu_model", "cores", "simd_target", "memory_gb", "hostname"}.
nlohmann::json MachineInfo();

// Cores this process may use (affinity mask), at least 1.
int AvailableCores();

}  // namespace hdr4d::bench
