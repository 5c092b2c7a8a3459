// Scenes of a suite made ready to train on: dataset folders as they are, datagen presets and
// built-in scenes generated on demand into a cache (once; a lock file keeps two harnesses from
// generating the same scene), and every scene's data checksum, which is part of each run's
// identity.
#pragma once

#include <filesystem>
#include <string>

#include "benchmark/suite.h"

namespace hdr4d::bench {

struct PreparedScene {
  const SceneSpec* spec = nullptr;
  std::filesystem::path dir;  // the dataset folder
  std::string checksum;       // DatasetChecksum(dir); a placeholder when not ready
  bool ready = true;          // false: a generated scene not made yet (generate off)
};

struct SceneCacheOptions {
  std::filesystem::path cache_dir;  // generated scenes live here
  std::filesystem::path hdr4d;      // the hdr4d binary that generates them
  bool verbose = true;              // say on stderr when a scene is generated
  bool generate = true;             // false: a scene not in the cache is returned not ready
};

// $HDR4D_CACHE, else $XDG_CACHE_HOME/hdr4d, else ~/.cache/hdr4d.
std::filesystem::path DefaultCacheDir();

// Where a generated scene lives in the cache (empty for a dataset folder).
std::filesystem::path CachedSceneDir(const SceneSpec& spec, const std::filesystem::path& cache);

// Generates the scene when it is not in the cache yet; throws hdr4d::Error naming the scene and
// the generator's log when generation fails, or a dataset folder that has no
// transforms_train.json.
PreparedScene PrepareScene(const SceneSpec& spec, const SceneCacheOptions& options);

// SHA-256 over the files a training run reads: transforms_{train,test,val}.json, point3d.ply,
// and every frame's LDR image and HDR ground truth, each named by its path relative to the
// scene (so moving the folder keeps the checksum). Throws hdr4d::Error naming a missing file.
std::string DatasetChecksum(const std::filesystem::path& dir);

}  // namespace hdr4d::bench
