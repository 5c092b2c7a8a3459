// Pictures of a dataset for people: a contact sheet of one camera over time, one row per
// exposure (the LDR images as stored) and a last row with the HDR ground truth tone-mapped by
// the mu-law of the evaluation protocol, so a scene can be judged at a glance.
#pragma once

#include <string>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/image/image.h"

namespace hdr4d {

// Lays equally sized images out in a grid (rows may be shorter; missing cells stay background).
// All images must have the same size; 1-channel images are shown grey. Output: RGB, kSrgb.
Image TileImages(const std::vector<std::vector<Image>>& rows,
                 int padding = 2,
                 float background = 0.1f);

// An HDR image for display: divided by its maximum, mu-law (mu = 5000), as the HDR metrics see it.
Image DisplayHdr(const Image& hdr);

struct PreviewOptions {
  std::string split = "test";  // train, test or val
  int camera_id = -1;          // -1: the split's first camera (all frames when there are no ids)
  int max_columns = 8;         // timestamps shown, evenly sampled over the sequence
  void Validate() const;
};

struct Preview {
  Image sheet;
  std::vector<std::string> row_labels;  // top to bottom
  std::vector<double> column_times;     // left to right (normalised time)
};

// Reads the chosen frames (LDR images, and HDR ground truth when present) and lays them out.
Preview MakeDatasetPreview(const Dataset& dataset, const PreviewOptions& options);

// What a sheet written to `file` shows, for people: "preview: FILE (R rows x C timestamps)", a
// line per row label, then the columns' times.
std::string DescribePreview(const Preview& preview, const std::string& file);

}  // namespace hdr4d
