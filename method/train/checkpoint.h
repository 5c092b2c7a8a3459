// Training checkpoints: the model, the optimiser state and whatever the trainer needs to
// continue exactly where it stopped (iteration, random state, densification statistics). One
// binary file: a magic word and version, a JSON header with the metadata and buffer sizes,
// then the raw little-endian float buffers and the Adam state, and a trailer with a 64-bit
// FNV-1a checksum of everything before it (damage anywhere is refused on load). Written to a
// temporary file and renamed, so an interrupted save never replaces the last good checkpoint.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/optim/adam.h"

namespace hdr4d::method {

struct Checkpoint {
  GaussianModel model;
  nlohmann::json trainer;                        // iteration, rng state, schedule state, ...
  std::vector<std::vector<float>> extra_floats;  // e.g. densification statistics
  std::string adam_state;                        // Adam::Save bytes
  std::string tone_mapper_state;                 // ToneMapper::Save bytes ("" = none)
};

void SaveCheckpoint(const std::filesystem::path& path, const Checkpoint& checkpoint);
// Throws hdr4d::Error naming the file for a missing, truncated, corrupt (checksum mismatch) or
// foreign file.
Checkpoint LoadCheckpoint(const std::filesystem::path& path);

}  // namespace hdr4d::method
