#include "benchmark/report_flip.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <optional>

#include "benchmark/report_images.h"
#include "benchmark/report_scene.h"
#include "benchmark/scoring.h"
#include "core/image/image_io.h"
#include "core/metrics/flip.h"
#include "core/metrics/hdr_alignment.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

std::optional<Image> ReadIfPresent(const fs::path& path) {
  if (!fs::exists(path)) return std::nullopt;
  return ReadImage(path);
}

// HDR-FLIP is not scale-free: the prediction times its scale against the truth (the tables'
// hdr_flip_aligned), else a model trained on per-image-maximum targets shows only its scale.
Image AlignedToTruth(const Image& pred, const Image& gt) {
  Image out = pred;
  const double scale = AlignHdr(pred, gt, nullptr).scale;
  for (float& v : out.values()) v = static_cast<float>(std::min(double(v) * scale, 3.0e38));
  return out;
}

// One cell: the magma map and its mean, or "-" when the pair is missing or cannot be scored
// (a render of another size; an all-black HDR truth has no exposure range).
std::string MapCell(const std::optional<Image>& pred, const std::optional<Image>& gt, bool hdr,
                    const std::string& alt, int* images) {
  if (!pred || !gt) return "<td class=\"na\">-</td>";
  try {
    const Image map = hdr ? HdrFlipMap(AlignedToTruth(pred->Rgb(), gt->Rgb()), gt->Rgb())
                          : FlipMap(pred->Rgb(), gt->Rgb());
    ++*images;
    return fmt::format("<td>{}<br>mean {:.4f}</td>",
                       HtmlImg(PngDataUri(FlipMagma(map)), alt,
                               std::min(256, std::max(160, map.width()))),
                       FlipMean(map));
  } catch (const Error& e) {
    return "<td class=\"na\">" + HtmlEscape(e.what()) + "</td>";
  }
}

}  // namespace

std::string FlipMapsHtml(const Frame& view, const std::vector<const RunSummary*>& runs,
                         int* images) {
  std::string h =
      "<p>FLIP error maps of the same view (NVIDIA's FLIP: 67 pixels per degree; HDR-FLIP over "
      "ACES exposures chosen from the ground truth, of the prediction times its scale against the "
      "truth as in the tables), magma from black (no visible difference) "
      "to pale yellow (1).</p>\n<table class=\"pics\"><thead><tr><th></th><th>LDR-FLIP</th>"
      "<th>HDR-FLIP</th></tr></thead><tbody>\n";
  const std::optional<Image> gt_ldr = ReadIfPresent(view.image_path);
  const std::optional<Image> gt_hdr =
      view.hdr_path ? ReadIfPresent(*view.hdr_path) : std::optional<Image>();
  for (const RunSummary* r : runs) {
    const fs::path renders =
        r->source == "submit" ? fs::path(r->run_dir) : fs::path(r->run_dir) / "renders";
    const std::string name = r->label.method + " (" + r->label.supervision + ")";
    h += "<tr><th>" + HtmlEscape(name) + "</th>";
    h += MapCell(ReadIfPresent(renders / LdrRenderName(view)), gt_ldr, false, name + " LDR-FLIP",
                 images);
    h += MapCell(ReadIfPresent(renders / HdrRenderName(view)), gt_hdr, true, name + " HDR-FLIP",
                 images);
    h += "</tr>\n";
  }
  return h + "</tbody></table>\n";
}

}  // namespace hdr4d::bench
