#include "method/render_run.h"

#include <algorithm>

#include "core/dataset.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "method/checkpoint.h"
#include "method/render.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

GaussianModel LoadRunModel(const fs::path& run) {
  return LoadCheckpoint(run / "checkpoint.bin").model;
}

int RenderRun(const RenderRunOptions& options) {
  const ThreadLimit limit(options.threads);
  const nlohmann::json config = ReadJsonFile(options.run / "config.json");
  if (!config.contains("data") || !config["data"].is_string()) {
    Fail("{}: key 'data' (the scene folder) missing", (options.run / "config.json").string());
  }
  const Split split = options.split == "train" ? Split::kTrain
                      : options.split == "test" ? Split::kTest
                      : options.split == "val"  ? Split::kVal
                                                : (Fail("render: unknown split '{}' (use train, test or val)", options.split), Split::kTest);
  const Dataset dataset = LoadDataset(config["data"].get<std::string>(), {.image_check = ImageCheck::kNone, .require_test = false});
  const GaussianModel model = LoadRunModel(options.run);
  const fs::path out = options.out.empty() ? options.run / "renders" / options.split : options.out;
  RenderOptions render;
  render.sh_degree = model.basis.max_sh_degree;
  render.time_degree = model.temporal ? model.basis.max_time_degree : 0;
  render.background.assign(model.channels, config.value("background", 0.0f));
  const std::vector<Frame>& frames = dataset.FramesOf(split);
  if (frames.empty()) Fail("{}: the {} split has no frames", dataset.root.string(), options.split);
  FrameState state;
  std::vector<float> values;
  Progress progress("render", static_cast<std::int64_t>(frames.size()));
  for (const Frame& f : frames) {
    const int w = f.camera.intrinsics.width, h = f.camera.intrinsics.height;
    values.resize(static_cast<std::size_t>(w) * h * model.channels);
    RenderForward(model, f.camera, static_cast<float>(f.time), render, &state, values.data());
    Image image(w, h, model.channels, Encoding::kSrgb);
    for (std::size_t i = 0; i < values.size(); ++i) image.values()[i] = std::clamp(values[i], 0.0f, 1.0f);
    // Named like the ground truth so `hdr4d eval` pairs them.
    fs::path name = f.image_path.filename();
    if (name.extension() != ".png") name += ".png";
    WriteImage(out / name, image);
    progress.Advance();
  }
  progress.Finish();
  return static_cast<int>(frames.size());
}

}  // namespace hdr4d::method
