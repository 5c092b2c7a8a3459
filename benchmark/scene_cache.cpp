#include "benchmark/scene_cache.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <vector>
#include <set>

#include "benchmark/child_process.h"
#include "benchmark/settings_flags.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/dataset/dataset_checksum.h"
#include "core/files/sha256.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

// An exclusive lock on a file for as long as the object lives.
class FileLock {
 public:
  explicit FileLock(const fs::path& path) {
    fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) Fail("{}: cannot create the lock file", path.string());
    if (flock(fd_, LOCK_EX) != 0) Fail("{}: cannot lock", path.string());
  }
  ~FileLock() {
    flock(fd_, LOCK_UN);
    close(fd_);
  }

 private:
  int fd_ = -1;
};

bool IsDataset(const fs::path& dir) { return fs::exists(dir / "transforms_train.json"); }

void Run(const std::vector<std::string>& argv, const fs::path& log, const std::string& scene) {
  const ChildResult r = RunChild({.argv = argv, .log = log});
  if (!r.ok())
    Fail("scene '{}': generating it failed ({}); see {}", scene, r.Describe(), log.string());
}

// Another dataset of the same scene, preset and seed in the cache (another camera pipeline's),
// whose renders may serve this one: `datagen --reuse-renders` takes them when the render plan
// is the same and renders otherwise. The bare <preset>-s<seed> folder first, then by name.
std::optional<fs::path> RenderSource(const SceneSpec& spec, const fs::path& dir) {
  const std::string prefix = fmt::format("{}-s{}", spec.source["preset"].get<std::string>(),
                                         spec.source["seed"].get<std::int64_t>());
  const std::string scene = spec.source["scene"].get<std::string>();
  std::error_code ec;
  std::vector<fs::path> found;
  for (const auto& e : fs::directory_iterator(dir.parent_path().parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (e.path() == dir.parent_path() || (name != prefix && name.rfind(prefix + "-", 0) != 0))
      continue;
    if (IsDataset(e.path() / scene) && fs::exists(e.path() / scene / "manifest.json"))
      found.push_back(e.path());
  }
  if (found.empty()) return std::nullopt;
  std::sort(found.begin(), found.end(), [&](const fs::path& a, const fs::path& b) {
    const bool bare_a = a.filename() == prefix, bare_b = b.filename() == prefix;
    return bare_a != bare_b ? bare_a : a < b;
  });
  return found.front();
}

}  // namespace

fs::path DefaultCacheDir() {
  if (const char* c = std::getenv("HDR4D_CACHE"); c && *c) return c;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "hdr4d";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache" / "hdr4d";
  return fs::temp_directory_path() / "hdr4d-cache";
}

fs::path CachedSceneDir(const SceneSpec& spec, const fs::path& cache) {
  switch (spec.kind) {
    case SceneSpec::Kind::kPath:
      return {};
    case SceneSpec::Kind::kDatagen: {
      std::string folder = fmt::format("{}-s{}", spec.source["preset"].get<std::string>(),
                                        spec.source["seed"].get<std::int64_t>());
      // Extra datagen flags make another dataset of the same renders: its own folder.
      if (spec.source.contains("flags") && !spec.source["flags"].empty())
        folder += fmt::format("-{}", Sha256Hex(spec.source["flags"].dump()).substr(0, 12));
      return cache / "datagen" / folder / spec.source["scene"].get<std::string>();
    }
    case SceneSpec::Kind::kBuiltin:
      // Named by the hash of its options: two suites asking for the same scene share it.
      return cache / "builtin" /
             fmt::format("{}-{}", spec.source["scene"].get<std::string>(),
                         Sha256Hex(spec.source.dump()).substr(0, 12));
  }
  return {};
}

PreparedScene PrepareScene(const SceneSpec& spec, const SceneCacheOptions& options) {
  PreparedScene p;
  p.spec = &spec;
  if (spec.kind == SceneSpec::Kind::kPath) {
    p.dir = spec.path;
    if (!IsDataset(p.dir))
      Fail("scene '{}': {} is not a dataset folder (no transforms_train.json)", spec.name,
           p.dir.string());
    p.checksum = DatasetChecksum(p.dir);
    return p;
  }
  p.dir = CachedSceneDir(spec, options.cache_dir);
  if (!options.generate && !IsDataset(p.dir)) {
    p.ready = false;  // listing only (bench run --dry-run): nothing is rendered or written
    p.checksum = "not generated: " + spec.name;  // keeps the runs of two such scenes apart
    return p;
  }
  std::error_code ec;
  fs::create_directories(p.dir.parent_path(), ec);
  if (ec) Fail("{}: cannot create the scene cache: {}", p.dir.parent_path().string(), ec.message());
  if (!IsDataset(p.dir)) {
    FileLock lock(p.dir.string() + ".lock");
    if (!IsDataset(p.dir)) {  // another harness may have made it while we waited
      const fs::path log = p.dir.string() + ".log";
      const std::string hdr4d = options.hdr4d.string();
      if (options.verbose)
        fmt::print(stderr, "bench: generating scene '{}' into {}\n", spec.name, p.dir.string());
      if (spec.kind == SceneSpec::Kind::kDatagen) {
        // datagen builds OUT/<scene>.partial and renames it into place when complete.
        std::vector<std::string> datagen = {
            hdr4d, "datagen", "--scene", spec.source["scene"].get<std::string>(), "--preset",
            spec.source["preset"].get<std::string>(), "--seed",
            std::to_string(spec.source["seed"].get<std::int64_t>()), "--out",
            p.dir.parent_path().string()};
        if (spec.source.contains("flags"))
          for (const std::string& a : SettingsToArgs(spec.source["flags"], 0, spec.name))
            datagen.push_back(a);
        // A suite's scenes keep the paper's train / test splits (and the cached scenes of earlier
        // harnesses stay valid) unless its flags ask datagen for a val split.
        if (!spec.source.contains("flags") || !spec.source["flags"].contains("val-every"))
          datagen.insert(datagen.end(), {"--val-every", "0"});
        if (const auto source = RenderSource(spec, p.dir))
          datagen.insert(datagen.end(), {"--reuse-renders", source->string()});
        Run(datagen, log, spec.name);
      } else {
        const fs::path partial = p.dir.string() + ".partial";
        fs::remove_all(partial, ec);
        const std::string scene = spec.source["scene"].get<std::string>();
        std::vector<std::string> make = {
            hdr4d, scene == "demo" ? "make-demo-scene" : "make-gaussian-scene", "--out",
            partial.string()};
        for (const std::string& a : SettingsToArgs(spec.source["flags"], 0, spec.name))
          make.push_back(a);
        Run(make, log, spec.name);
        if (scene == "demo") {
          std::vector<std::string> synth = {hdr4d, "synth-ldr", "--data", partial.string()};
          for (const std::string& a : SettingsToArgs(spec.source["synth"], 0, spec.name))
            synth.push_back(a);
          Run(synth, log, spec.name);
        }
        fs::rename(partial, p.dir, ec);
        if (ec)
          Fail("{}: cannot move the generated scene into place: {}", p.dir.string(), ec.message());
      }
      if (!IsDataset(p.dir))
        Fail("scene '{}': the generator finished but {} holds no dataset; see {}", spec.name,
             p.dir.string(), log.string());
    }
  }
  p.checksum = DatasetChecksum(p.dir);
  return p;
}

std::string DatasetChecksum(const fs::path& dir) {
  const Dataset d = LoadDataset(dir, {.image_check = ImageCheck::kNone, .require_test = false});
  std::string listing;
  for (const auto& [f, hash] : HashDatasetFiles(d))
    listing += fs::relative(f, dir).generic_string() + " " + hash + "\n";
  return Sha256Hex(listing);
}

}  // namespace hdr4d::bench
