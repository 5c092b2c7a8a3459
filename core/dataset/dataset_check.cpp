// CheckDataset: a scene's files read, its images inspected, its cameras, sizes, duplicates and
// times checked, every problem with file, frame and key (ARCHITECTURE §3).
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <memory>
#include <set>

#include "core/dataset/dataset_detail.h"
#include "core/dataset/dataset_image_rules.h"
#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/image/image_io.h"
#include "core/files/output_guard.h"
#include "core/util/parallel.h"
#include "core/geometry/ply.h"
#include "core/util/progress.h"

namespace hdr4d {
using namespace dataset_detail;

namespace {

struct ImageResult {
  std::optional<ImageSpecInfo> ldr, hdr;
  std::string ldr_error, hdr_error;
};

// What the images said: per frame (in frame order) and the size every image must have.
struct ImageSizes {
  std::vector<ImageResult> images;
  bool probe_failed = false;  // kNone: reported once, not again for every unsized frame
  std::optional<std::pair<int, int>> reference_size;
  std::string reference_name;
};

// Reads one image as deeply as `check` says and applies the rules of its role (LDR file_path or
// HDR exr_file_path, core/dataset/dataset_image_rules.h): what training would refuse is found here.
ImageSpecInfo Inspect(const fs::path& path, ImageCheck check, bool hdr) {
  ImageSpecInfo spec;
  std::string problem;
  if (check == ImageCheck::kFull) {
    const Image image = ReadImage(path);  // rejects NaN/Inf pixels
    spec = {image.width(), image.height(), image.channels(), image.encoding() == Encoding::kLinear};
    problem = hdr ? HdrImageProblem(image) : LdrImageProblem(image);
  } else {
    spec = ReadImageSpec(path);
    problem = hdr ? HdrImageHeaderProblem(spec) : LdrImageHeaderProblem(spec);
  }
  if (!problem.empty()) Fail("{}: {}", path.string(), problem);
  return spec;
}

// Smaller scenes check in well under a second: a bar would only be noise.
constexpr std::size_t kProgressMinFrames = 200;

void CheckImages(std::vector<PendingFrame*>& frames,
                 const DatasetLoadOptions& options,
                 std::vector<ImageResult>& results) {
  results.assign(frames.size(), {});
  std::unique_ptr<Progress> progress;
  if (options.show_progress && frames.size() >= kProgressMinFrames) {
    progress = std::make_unique<Progress>("check images", static_cast<std::int64_t>(frames.size()));
  }
  ParallelFor(static_cast<std::int64_t>(frames.size()), 1, [&](std::int64_t i) {
    const Frame& f = frames[i]->frame;
    ImageResult& result = results[i];
    if (!f.image_path.empty()) {
      try {
        result.ldr = Inspect(f.image_path, options.image_check, /*hdr=*/false);
      } catch (const std::exception& e) {
        result.ldr_error = e.what();
      }
    }
    if (f.hdr_path) {
      try {
        result.hdr = Inspect(*f.hdr_path, options.image_check, /*hdr=*/true);
      } catch (const std::exception& e) {
        result.hdr_error = e.what();
      }
    }
    if (progress) progress->Advance();
  });
  if (progress) progress->Finish();
}

std::string SizeString(int w, int h) { return fmt::format("{}x{}", w, h); }

void InspectImages(std::vector<PendingFrame*>& frames,
                   const DatasetLoadOptions& options,
                   ProblemSink& sink,
                   ImageSizes& sizes) {
  std::vector<ImageResult>& images = sizes.images;
  bool& probe_failed = sizes.probe_failed;
  // Images: every header (or every pixel) in parallel, problems reported in frame order.
  if (options.image_check != ImageCheck::kNone) {
    CheckImages(frames, options, images);
  } else {
    // Size the cameras that declare no w/h from one image: every frame shares its size.
    images.assign(frames.size(), {});
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const PendingFrame& p = *frames[i];
      if ((p.keys.w && p.keys.h) || p.frame.image_path.empty()) continue;
      std::string why;
      for (const std::optional<fs::path>& path :
           {std::optional<fs::path>(p.frame.image_path), p.frame.hdr_path}) {
        if (!path) continue;
        try {
          images[i].ldr = ReadImageSpec(*path);
          break;
        } catch (const std::exception& e) {
          if (why.empty()) why = e.what();
        }
      }
      if (!images[i].ldr) {
        sink.Add(p.rank, p.json_path, p.frame.index, "file_path",
                 fmt::format("cannot size the camera (no w/h given): {}", why));
        probe_failed = true;
        frames[i]->image_ok = false;
      }
      break;
    }
  }
}

// The size every image must have: the most common LDR size (ties: the first seen), so one odd
// image is the one reported, whichever frame it is.
void FindReferenceSize(const std::vector<PendingFrame*>& frames, ImageSizes& sizes) {
  const std::vector<ImageResult>& images = sizes.images;
  std::optional<std::pair<int, int>>& reference_size = sizes.reference_size;
  std::string& reference_name = sizes.reference_name;
  std::map<std::pair<int, int>, std::pair<int, std::size_t>> counts;  // size -> (count, first)
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!images[i].ldr) continue;
    auto [it, inserted] = counts.try_emplace({images[i].ldr->width, images[i].ldr->height}, 0, i);
    ++it->second.first;
  }
  std::size_t first = 0;
  int best = 0;
  for (const auto& [size, count_first] : counts) {
    const auto [count, first_index] = count_first;
    if (count > best || (count == best && first_index < first)) {
      best = count;
      first = first_index;
      reference_size = size;
    }
  }
  if (reference_size) {
    reference_name = fmt::format("frame {} of {}", frames[first]->frame.index,
                                 frames[first]->json_path.filename().string());
  }
}

// Every image against its declared size or the reference size, HDR against its LDR image.
void CheckImageSizes(std::vector<PendingFrame*>& frames,
                     const ImageSizes& sizes,
                     ProblemSink& sink) {
  const std::vector<ImageResult>& images = sizes.images;
  const std::optional<std::pair<int, int>>& reference_size = sizes.reference_size;
  const std::string& reference_name = sizes.reference_name;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    PendingFrame& p = *frames[i];
    const ImageResult& img = images[i];
    const Frame& f = p.frame;
    auto add = [&](const char* key, std::string message) {
      sink.Add(p.rank, p.json_path, f.index, key, std::move(message));
      p.image_ok = false;
    };
    if (!img.ldr_error.empty()) add("file_path", img.ldr_error);
    if (!img.hdr_error.empty()) add("exr_file_path", img.hdr_error);
    // Expected size: declared, else the reference.
    std::optional<std::pair<int, int>> expected = reference_size;
    if (p.keys.w || p.keys.h) {
      const int w = p.keys.w.value_or(reference_size ? reference_size->first : 0);
      const int h = p.keys.h.value_or(reference_size ? reference_size->second : 0);
      expected = {w, h};
      if (img.ldr && (img.ldr->width != w || img.ldr->height != h)) {
        add("file_path",
            fmt::format("{}: image is {}, but w, h declare {}", f.image_path.string(),
                        SizeString(img.ldr->width, img.ldr->height), SizeString(w, h)));
        expected.reset();
      }
    } else if (img.ldr && reference_size &&
               (img.ldr->width != reference_size->first ||
                img.ldr->height != reference_size->second)) {
      add("file_path",
          fmt::format("{}: image is {}, but most images are {} (e.g. {}); every image must have "
                      "the same size",
                      f.image_path.string(), SizeString(img.ldr->width, img.ldr->height),
                      SizeString(reference_size->first, reference_size->second), reference_name));
    }
    if (img.hdr) {
      if (img.ldr && (img.hdr->width != img.ldr->width || img.hdr->height != img.ldr->height)) {
        add("exr_file_path",
            fmt::format("{}: HDR image is {}, its LDR image {} is {}", f.hdr_path->string(),
                        SizeString(img.hdr->width, img.hdr->height), f.image_path.string(),
                        SizeString(img.ldr->width, img.ldr->height)));
      } else if (!img.ldr && expected &&
                 (img.hdr->width != expected->first || img.hdr->height != expected->second)) {
        add("exr_file_path", fmt::format("{}: HDR image is {}, expected {}", f.hdr_path->string(),
                                         SizeString(img.hdr->width, img.hdr->height),
                                         SizeString(expected->first, expected->second)));
      }
    }
  }
}

// Intrinsics from the keys, the file's camera_angle_x and the image size.
void SetIntrinsics(std::vector<PendingFrame*>& frames,
                   const std::array<SplitFile, 3>& files,
                   const ImageSizes& sizes,
                   const DatasetLoadOptions& options,
                   ProblemSink& sink) {
  const std::vector<ImageResult>& images = sizes.images;
  const std::optional<std::pair<int, int>>& reference_size = sizes.reference_size;
  const bool probe_failed = sizes.probe_failed;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    PendingFrame& p = *frames[i];
    Frame& f = p.frame;
    const SplitFile& file = files[static_cast<int>(f.split)];
    int w = p.keys.w.value_or(0), h = p.keys.h.value_or(0);
    const ImageSpecInfo* size = images[i].ldr ? &*images[i].ldr : nullptr;
    if (!size && reference_size && options.image_check == ImageCheck::kNone) {
      w = w ? w : reference_size->first;
      h = h ? h : reference_size->second;
    } else if (size) {
      w = w ? w : size->width;
      h = h ? h : size->height;
    }
    if (w <= 0 || h <= 0) {
      if (p.image_ok && !probe_failed && !f.image_path.empty()) {
        sink.Add(p.rank, p.json_path, f.index, "w",
                 "image size unknown: declare w and h or provide the image");
      }
      continue;
    }
    PinholeIntrinsics& k = f.camera.intrinsics;
    k.width = w;
    k.height = h;
    if (p.keys.fl_x) {
      k.fx = *p.keys.fl_x;
    } else if (file.camera_angle_x) {
      k.fx = PinholeIntrinsics::FromFovX(*file.camera_angle_x, w, h).fx;
    } else {
      continue;  // reported once per file while parsing
    }
    k.fy = p.keys.fl_y.value_or(k.fx);
    k.cx = p.keys.cx.value_or(0.5 * w);
    k.cy = p.keys.cy.value_or(0.5 * h);
    if (std::string problem = k.Problem(); !problem.empty()) {
      sink.Add(p.rank, p.json_path, f.index, "fl_x", problem);
    }
  }
}

// Duplicate images within a split; an image of two splits read at two exposures (one of the
// frames has the wrong image, and synth-ldr writes the file twice; at one exposure a split may
// reuse another's image, to score a training view); one HDR image for frames of different
// times or poses (merge-hdr would fuse them).
void CheckDuplicates(const std::array<SplitFile, 3>& files, bool hdrnerf, ProblemSink& sink) {
  std::map<fs::path, const PendingFrame*> first_use;  // over every split
  std::map<fs::path, const PendingFrame*> first_hdr;
  for (const SplitFile& file : files) {
    std::map<fs::path, int> seen;
    for (const PendingFrame& p : file.frames) {
      if (p.frame.image_path.empty()) continue;
      const auto [it, inserted] = seen.emplace(p.frame.image_path, p.frame.index);
      const auto [other, first] = first_use.emplace(p.frame.image_path, &p);
      if (!inserted) {
        sink.Add(p.rank, p.json_path, p.frame.index, "file_path",
                 fmt::format("{} is already used by frame {} of this file",
                             p.frame.image_path.string(), it->second));
      } else if (!first && !hdrnerf && other->second->frame.exposure != p.frame.exposure) {
        const Frame& o = other->second->frame;
        sink.Add(p.rank, p.json_path, p.frame.index, "file_path",
                 fmt::format("{} is also frame {} of {} at another exposure ({} s there, {} s "
                             "here): one image cannot be both",
                             p.frame.image_path.string(), o.index,
                             other->second->json_path.filename().string(), o.exposure,
                             p.frame.exposure));
      }
    }
  }
  for (const SplitFile& file : files) {
    for (const PendingFrame& p : file.frames) {
      if (!p.frame.hdr_path) continue;
      const auto [it, first] = first_hdr.emplace(*p.frame.hdr_path, &p);
      if (first) continue;
      const Frame& o = it->second->frame;
      const bool same_pose =
          (o.camera.world_from_cam_gl - p.frame.camera.world_from_cam_gl).cwiseAbs().maxCoeff() <=
          1e-9;
      if (o.time_raw == p.frame.time_raw && same_pose) continue;
      sink.Add(p.rank, p.json_path, p.frame.index, "exr_file_path",
               fmt::format("{} is also the HDR image of frame {} of {}, which shows {} (time {} "
                           "there, {} here): frames sharing HDR ground truth must be one view at "
                           "one time",
                           p.frame.hdr_path->string(), o.index,
                           it->second->json_path.filename().string(),
                           same_pose ? "another time" : "another pose", o.time_raw,
                           p.frame.time_raw));
    }
  }
}

// The frames as a Dataset: times normalised by the largest over every split (or per file, as
// the reference does), the scene-wide values from the training file, the layout named.
Dataset AssembleDataset(const fs::path& root,
                        SceneFiles& scene,
                        const std::vector<PendingFrame*>& frames,
                        const DatasetLoadOptions& options) {
  std::array<SplitFile, 3>& files = scene.files;
  Dataset dataset;
  dataset.root = root;
  double global_max = 0;
  for (const PendingFrame* p : frames) global_max = std::max(global_max, p->frame.time_raw);
  dataset.time_max_raw = global_max;
  for (SplitFile& file : files) {
    double file_max = 0;
    for (const PendingFrame& p : file.frames) file_max = std::max(file_max, p.frame.time_raw);
    const double divisor =
        options.time_normalisation == TimeNormalisation::kGlobal ? global_max : file_max;
    for (PendingFrame& p : file.frames) {
      p.frame.time = divisor > 1 ? p.frame.time_raw / divisor : p.frame.time_raw;
    }
  }

  for (SplitFile& file : files) {
    std::vector<Frame>& out = file.split == Split::kTrain  ? dataset.train
                              : file.split == Split::kTest ? dataset.test
                                                           : dataset.val;
    out.reserve(file.frames.size());
    for (PendingFrame& p : file.frames) out.push_back(std::move(p.frame));
  }
  dataset.near = files[0].near;
  dataset.far = files[0].far;
  if (files[0].camera_angle_x) {
    dataset.camera_angle_x = *files[0].camera_angle_x;
  } else if (!dataset.train.empty() && dataset.train[0].camera.intrinsics.fx > 0) {
    dataset.camera_angle_x = dataset.train[0].camera.intrinsics.FovX();
  }
  dataset.layout = LayoutName(scene, dataset);
  return dataset;
}

// point3d.ply (or nerfstudio's ply_file_path) for initialisation, with its point count.
void AttachPointCloud(const fs::path& root,
                      const SceneFiles& scene,
                      ProblemSink& sink,
                      Dataset& dataset,
                      DatasetReport& report) {
  std::error_code ec;
  const fs::path ply_path = scene.nerfstudio_ply.value_or(root / "point3d.ply");
  if (scene.nerfstudio_ply && !fs::exists(ply_path, ec)) {
    sink.Add(SplitRank(Split::kTrain, false), root / "transforms.json", -1, "ply_file_path",
             ply_path.string() + " not found");
  } else if (fs::exists(ply_path, ec)) {
    dataset.point_cloud_path = ply_path;
    try {
      report.point_cloud_points = static_cast<std::int64_t>(ReadPly(ply_path).size());
    } catch (const Error& e) {
      sink.Add(kRankPointCloud, ply_path, -1, "", WithoutPathPrefix(e.what(), ply_path));
    }
  }
}

// The files a scene is made of and the folders holding its images are inputs of whatever read
// it: no writer of this process may replace them or add files among the images
// (core/files/output_guard.h), so renders never land on or beside ground truth.
void ProtectScene(const Dataset& dataset, const std::vector<fs::path>& json_files) {
  const std::string scene = dataset.root.string();
  const std::string file_role =
      fmt::format("a file of dataset {} (a command never overwrites its inputs)", scene);
  const std::string image_role =
      fmt::format("an image of dataset {} (ground truth is never overwritten)", scene);
  for (const fs::path& f : json_files) ProtectInputFile(f, file_role);
  if (dataset.point_cloud_path) ProtectInputFile(*dataset.point_cloud_path, file_role);
  std::set<fs::path> folders;
  for (const Frame* f : dataset.AllFrames()) {
    for (const std::optional<fs::path>& path :
         {f->image_path.empty() ? std::nullopt : std::optional<fs::path>(f->image_path),
          f->hdr_path}) {
      if (!path) continue;
      ProtectInputFile(*path, image_role);
      folders.insert(path->parent_path());
    }
  }
  for (const fs::path& folder : folders) {
    ProtectInputFolder(folder,
                       fmt::format("the images of dataset {} (write outputs elsewhere)", scene));
  }
}

}  // namespace

DatasetReport CheckDataset(const fs::path& root, const DatasetLoadOptions& options) {
  DatasetReport report;
  ProblemSink sink;
  // "folder not found" only when nothing is there: an unreadable folder says so.
  if (std::string problem = InputFolderProblem(root); !problem.empty()) {
    if (ProbePath(root).kind == PathKind::kFile || ProbePath(root).kind == PathKind::kOther)
      problem = "not a folder (a dataset is a folder with transforms_*.json)";
    sink.Add(kRankRoot, root, -1, "", problem);
    report.problems = sink.Sorted();
    return report;
  }
  if (!HasTransforms(root)) {
    CheckOtherLayout(root, options, sink, report);
    report.problems = sink.Sorted();
    return report;
  }
  SceneFiles scene = ReadSceneFiles(root, options, sink);
  const bool stops_like = ReportStopsLikeExposures(scene, options, sink);
  ReportMissingPerFrameKeys(scene, sink);
  if (!scene.files[0].parsed) {
    report.problems = sink.Sorted();
    return report;
  }
  std::vector<PendingFrame*> frames;
  for (SplitFile& file : scene.files) {
    for (PendingFrame& p : file.frames) frames.push_back(&p);
  }
  ImageSizes sizes;
  InspectImages(frames, options, sink, sizes);
  FindReferenceSize(frames, sizes);
  CheckImageSizes(frames, sizes, sink);
  SetIntrinsics(frames, scene.files, sizes, options, sink);
  CheckDuplicates(scene.files, scene.hdrnerf, sink);
  Dataset dataset = AssembleDataset(root, scene, frames, options);
  dataset.exposure_unit = options.exposure_unit;
  dataset.exposures_look_like_stops = stops_like;
  AttachPointCloud(root, scene, sink, dataset, report);
  if (options.protect_inputs) ProtectScene(dataset, scene.json_files);
  report.dataset = std::move(dataset);
  report.problems = sink.Sorted();
  return report;
}

Dataset LoadDataset(const fs::path& root, const DatasetLoadOptions& options) {
  DatasetReport report = CheckDataset(root, options);
  if (report.problems.empty()) {
    HDR4D_CHECK(report.dataset.has_value());
    return std::move(*report.dataset);
  }
  // One line, as every user-facing error: the first problem, and where to see the rest.
  std::string message = report.problems.front().ToString();
  if (report.problems.size() > 1) {
    message +=
        fmt::format(" (and {} more problem{}: run `hdr4d dataset check {}{}` for all)",
                    report.problems.size() - 1, report.problems.size() == 2 ? "" : "s",
                    options.exposure_unit == ExposureUnit::kStops ? "--exposure-unit stops " : "",
                    root.string());
  }
  throw Error(message);
}

}  // namespace hdr4d
