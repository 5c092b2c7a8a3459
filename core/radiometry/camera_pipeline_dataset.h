// A camera pipeline over a dataset: one view per HDR image (a camera at a time; the frames
// that share it are its exposure brackets), their statistics read once, the processing
// planned over the whole sequence (auto-exposure needs every timestamp), and the record for
// synthesis.json.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/radiometry/camera_pipeline.h"

namespace hdr4d {

class DatasetPipeline {
 public:
  // frames: every frame that will be synthesised (each with an hdr_path). crf_spec: the
  // dataset's response. Reads each HDR image once when the pipeline meters the content
  // (auto-exposure, phone). A frame's camera is its camera_id, or, when the JSON gives none,
  // the index of its distinct transform_matrix.
  DatasetPipeline(const CameraPipelineOptions& options, const std::string& crf_spec,
                  const std::vector<const Frame*>& frames);

  // The frame's LDR image from its HDR image (linear RGB). Byte-identical to SynthesizeLdr
  // for the identity pipeline.
  Image Synthesize(const Image& hdr, const Frame& frame, const Crf& base,
                   const LdrSynthesisOptions& ldr) const;

  bool Identity() const { return options_.IsIdentity(); }
  // The options and, per view, its HDR file (relative to `root`), camera, time and
  // ViewProcessing: the hidden truth.
  nlohmann::json ToJson(const std::filesystem::path& root) const;

 private:
  CameraPipelineOptions options_;
  std::map<std::filesystem::path, std::size_t> view_of_hdr_;
  std::vector<std::filesystem::path> hdr_of_view_;
  std::vector<PipelineView> views_;
  std::vector<ViewProcessing> processing_;
  double reference_exposure_ = 1;
};

}  // namespace hdr4d
