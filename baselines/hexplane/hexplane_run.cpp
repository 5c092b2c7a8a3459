// A HexPlane run folder: config.json (the method, scene, resolution and the HexPlane settings),
// checkpoint.bin (HexPlaneModel::Save) and results.json, like the Gaussian runs'; read back
// here for `hdr4d render`.
#include <fmt/format.h>

#include "baselines/hexplane/hexplane_render.h"
#include "baselines/hexplane/hexplane_run.h"
#include "core/dataset/dataset.h"
#include "core/files/atomic_file.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/util/progress.h"

namespace hdr4d::baselines::hexplane {
namespace fs = std::filesystem;

bool IsHexPlaneRun(const fs::path& run) {
  const fs::path config = run / "config.json";
  if (!fs::exists(config)) return false;
  const nlohmann::json j = ReadJsonFile(config);
  return j.is_object() && j.contains("hexplane");
}

LoadedHexPlaneRun LoadHexPlaneRun(const fs::path& run, int resolution_override) {
  LoadedHexPlaneRun r;
  const fs::path config_path = run / "config.json";
  const nlohmann::json j = ReadJsonFile(config_path);
  const JsonField config(j, config_path.string());
  r.config = HexPlaneConfig::FromJson(j["hexplane"], config_path.string());
  r.resolution = resolution_override > 0
                     ? resolution_override
                     : static_cast<int>(config.IntOr("resolution", 1, 1, 1 << 16));
  r.dataset = LoadDataset(config["data"].String(),
                          {.image_check = ImageCheck::kNone, .require_test = false});
  r.model = HexPlaneModel::Load(run / "checkpoint.bin", r.config);
  return r;
}

int RenderHexPlaneRun(const HexPlaneRenderOptions& options) {
  const LoadedHexPlaneRun run = LoadHexPlaneRun(options.run, options.resolution);
  const Split split = ParseSplit(options.split, "render");
  const std::vector<Frame>& frames = run.dataset.FramesOf(split);
  if (frames.empty())
    Fail("{}: the {} split has no frames", run.dataset.root.string(), options.split);
  const fs::path out = options.out.empty() ? options.run / "renders" / options.split : options.out;
  CheckOutputFolder(out);
  FileBatch batch;  // the renders replace an earlier run's all together (atomic_file.h)
  Progress progress("render", static_cast<std::int64_t>(frames.size()));
  std::vector<float> ldr, hdr;
  int written = 0;
  for (const Frame& f : frames) {
    Camera camera = f.camera;
    camera.intrinsics = method::DownscaledIntrinsics(f.camera.intrinsics, run.resolution);
    const int w = camera.intrinsics.width, h = camera.intrinsics.height;
    RenderView(run.model, camera, float(f.time), options.exposure.value_or(f.exposure), -1, &ldr,
               options.write_hdr ? &hdr : nullptr);
    // Named like the ground truth so `hdr4d eval` pairs them (as method/run/render_split.cpp).
    fs::path name = f.image_path.filename();
    if (name.extension() != ".png") name += ".png";
    WriteImage(out / name, DisplayImageFromBuffer(ldr.data(), w, h, 3),
               {.png_compression = options.png_compression, .batch = &batch});
    ++written;
    if (options.write_hdr && !hdr.empty()) {
      fs::path hdr_name = f.hdr_path ? f.hdr_path->filename() : f.image_path.stem();
      if (hdr_name.extension() != ".exr") hdr_name += ".exr";
      Image image(w, h, 3, Encoding::kLinear);
      std::copy(hdr.begin(), hdr.end(), image.data());
      WriteImage(out / hdr_name, image, {.format = PixelFormat::kFloat, .batch = &batch});
      ++written;
    }
    progress.Advance();
  }
  progress.Finish();
  batch.Commit();
  return written;
}

}  // namespace hdr4d::baselines::hexplane
