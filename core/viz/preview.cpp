#include "core/viz/preview.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/dataset/dataset_image_rules.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/metrics/metrics.h"

namespace hdr4d {

Image TileImages(const std::vector<std::vector<Image>>& rows, int padding, float background) {
  int w = 0, h = 0, columns = 0;
  for (const auto& row : rows) {
    columns = std::max(columns, static_cast<int>(row.size()));
    for (const Image& image : row) {
      if (image.empty()) continue;
      if (w == 0) w = image.width(), h = image.height();
      if (image.width() != w || image.height() != h) {
        Fail("contact sheet: images differ in size ({} vs {}x{})", image.ShapeString(), w, h);
      }
    }
  }
  if (w == 0) Fail("contact sheet: no images to lay out");
  const int n_rows = static_cast<int>(rows.size());
  Image sheet(columns * w + (columns + 1) * padding, n_rows * h + (n_rows + 1) * padding, 3,
              Encoding::kSrgb, background);
  for (int r = 0; r < n_rows; ++r) {
    for (int c = 0; c < static_cast<int>(rows[r].size()); ++c) {
      const Image& image = rows[r][c];
      if (image.empty()) continue;
      const int x0 = padding + c * (w + padding), y0 = padding + r * (h + padding);
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          for (int k = 0; k < 3; ++k) {
            sheet.at(x0 + x, y0 + y, k) = image.at(x, y, std::min(k, image.channels() - 1));
          }
        }
      }
    }
  }
  return sheet;
}

Image DisplayHdr(const Image& hdr) {
  Image scaled = hdr.Rgb();  // the colour: alpha is no radiance
  const float max_value = scaled.MaxValue();
  if (!(max_value > 0) || !std::isfinite(max_value))
    Fail("HDR display: the image has no positive finite maximum");
  for (float& v : scaled.values()) v = std::max(v, 0.0f) / max_value;
  Image shown = MuLaw(scaled);
  shown.set_encoding(Encoding::kSrgb);  // a display image now
  return shown;
}

void PreviewOptions::Validate() const {
  ParseSplit(split, "preview");
  if (max_columns < 1) Fail("preview: --columns must be at least 1, got {}", max_columns);
}

Preview MakeDatasetPreview(const Dataset& dataset, const PreviewOptions& options) {
  options.Validate();
  const Split split = ParseSplit(options.split, "preview");
  const std::vector<Frame>& frames = dataset.FramesOf(split);
  if (frames.empty())
    Fail("{}: the {} split has no frames to preview", dataset.root.string(), options.split);
  int camera = options.camera_id;
  if (camera < 0) camera = frames.front().camera_id;  // -1 when the dataset has no camera ids
  // time -> exposure -> frame, for the chosen camera.
  std::map<double, std::map<double, const Frame*>> by_time;
  std::map<double, int> exposure_rows;
  for (const Frame& f : frames) {
    if (f.camera_id != camera) continue;
    by_time[f.time].emplace(f.exposure, &f);
    exposure_rows.emplace(f.exposure, 0);
  }
  if (by_time.empty())
    Fail("{}: no {} frame has camera_id {}", dataset.root.string(), options.split, camera);
  int row = 0;
  for (auto& [exposure, index] : exposure_rows) index = row++;

  // Evenly sampled columns over the sequence.
  std::vector<double> times;
  for (const auto& [t, unused] : by_time) times.push_back(t);
  std::vector<double> columns;
  const int n = std::min<int>(options.max_columns, static_cast<int>(times.size()));
  for (int c = 0; c < n; ++c) {
    const std::size_t i =
        n == 1 ? 0 : static_cast<std::size_t>(std::lround(c * (times.size() - 1.0) / (n - 1)));
    columns.push_back(times[i]);
  }

  Preview preview;
  preview.column_times = columns;
  const bool any_hdr = std::any_of(frames.begin(), frames.end(), [&](const Frame& f) {
    return f.camera_id == camera && f.hdr_path;
  });
  std::vector<std::vector<Image>> grid(exposure_rows.size() + (any_hdr ? 1 : 0),
                                       std::vector<Image>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) {
    for (const auto& [exposure, frame] : by_time[columns[c]]) {
      grid[exposure_rows[exposure]][c] = ExpandToRgb(ReadImage(frame->image_path));
      // The dataset's rules for HDR ground truth, which name the file (an all-black image too).
      if (any_hdr && frame->hdr_path && grid.back()[c].empty())
        grid.back()[c] = DisplayHdr(ReadHdrGroundTruth(*frame->hdr_path));
    }
  }
  for (const auto& [exposure, index] : exposure_rows)
    preview.row_labels.push_back(fmt::format("LDR at {} s", exposure));
  if (any_hdr) preview.row_labels.push_back("HDR ground truth, mu-law of x / max");
  preview.sheet = TileImages(grid);
  return preview;
}

std::string DescribePreview(const Preview& preview, const std::string& file) {
  std::string out = fmt::format("preview: {} ({} rows x {} timestamps)\n", file,
                                preview.row_labels.size(), preview.column_times.size());
  for (std::size_t r = 0; r < preview.row_labels.size(); ++r)
    out += fmt::format("  row {}: {}\n", r + 1, preview.row_labels[r]);
  std::string times;
  for (double t : preview.column_times)
    times += fmt::format("{}{:.3g}", times.empty() ? "" : ", ", t);
  return out + fmt::format("  columns: t = {}\n", times);
}

}  // namespace hdr4d
