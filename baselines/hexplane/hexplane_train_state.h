// A resumable HexPlane checkpoint: the model (HexPlaneModel::Write), then the trainer's state:
// iterations done, training seconds, its random generator, where it is in the current
// permutation of the training pixels, and Adam's moments. `hdr4d render` reads the model part
// alone (HexPlaneModel::Load stops after it); `hdr4d train --resume` reads both and continues
// exactly as if never stopped (same thread count: the ray lanes sum gradients per thread).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "baselines/hexplane/hexplane_adam.h"
#include "baselines/hexplane/hexplane_model.h"

namespace hdr4d::baselines::hexplane {

struct HexPlaneTrainState {
  std::int64_t iteration = 0;  // iterations done
  double seconds = 0;          // training time so far
  std::string rng;             // the trainer's std::mt19937_64, in its text form
  // The pixel order: identity shuffled by mt19937_64(epoch_seed), `next` of it used; no
  // permutation drawn yet when !in_epoch.
  std::uint64_t epoch_seed = 0, next = 0;
  bool in_epoch = false;
  // The training curve so far: (iteration, loss, batch PSNR) triples, for results.json.
  std::vector<double> curve;
};

void SaveTrainingCheckpoint(const std::filesystem::path& file, const HexPlaneModel& model,
                            const PlainAdam& adam, const HexPlaneTrainState& state);
// Throws hdr4d::Error naming the file when it is no HexPlane checkpoint, is cut short, or holds a
// model without the trainer's state (a checkpoint written before resuming was possible).
HexPlaneTrainState LoadTrainingCheckpoint(const std::filesystem::path& file,
                                          const HexPlaneConfig& config, HexPlaneModel* model,
                                          PlainAdam* adam);

}  // namespace hdr4d::baselines::hexplane
