// Training checkpoints: the model, the optimiser state and whatever the trainer needs to
// continue exactly where it stopped (iteration, random state, densification statistics). One
// binary file: a magic word and version, a JSON header with the metadata and buffer sizes,
// then the raw little-endian float buffers and the Adam state, and a trailer with a 64-bit
// FNV-1a checksum of everything before it (damage anywhere is refused on load). Written to a
// temporary file and renamed, so an interrupted save never replaces the last good checkpoint.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
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

// A length-prefixed state section (the optimiser's, the tone mapper's): its exact size and what
// writes those bytes, so a live state is streamed into the file instead of copied first.
struct CheckpointSection {
  std::uint64_t size = 0;
  std::function<void(std::ostream&)> write;  // may be empty when size is 0

  static CheckpointSection Of(std::string_view bytes);
  static CheckpointSection Of(const Adam& adam);
};

// What a checkpoint holds, by reference: a training run saves its live model and optimiser
// (most of its memory) without a copy of either. Every pointer must be set.
struct CheckpointParts {
  const GaussianModel* model = nullptr;
  const nlohmann::json* trainer = nullptr;
  std::vector<const std::vector<float>*> extra_floats;
  CheckpointSection adam_state, tone_mapper_state;
};

void SaveCheckpoint(const std::filesystem::path& path, const CheckpointParts& parts);
void SaveCheckpoint(const std::filesystem::path& path, const Checkpoint& checkpoint);
// What to load besides the model, the trainer state and the extra buffers.
struct CheckpointLoadOptions {
  // false: skip the optimiser's state (adam_state stays empty; it is still checksummed). A run
  // that is only looked at (render, export) needs no Adam moments: two thirds of the file.
  bool optimizer_state = true;
};

// Throws hdr4d::Error naming the file for a missing, truncated, corrupt (checksum mismatch) or
// foreign file.
Checkpoint LoadCheckpoint(const std::filesystem::path& path,
                          const CheckpointLoadOptions& options = {});

}  // namespace hdr4d::method
