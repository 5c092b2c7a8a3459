#include "method/run/viewer_page.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "method/run/gaussian_4d_ply.h"
#include "method/run/tone_tables.h"
#include "method/run/viewer_assets.h"  // generated from viewer/ (method/run/CMakeLists.txt)

namespace hdr4d::method {
namespace {

std::string Base64(const void* data, std::size_t size) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const unsigned v = (p[i] << 16) | (i + 1 < size ? p[i + 1] << 8 : 0) | (i + 2 < size ? p[i + 2] : 0);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < size ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < size ? kDigits[v & 63] : '=';
  }
  return out;
}

nlohmann::json CameraJson(const Frame& f, const char* split, int index) {
  const Eigen::Matrix4d m = f.camera.CamFromWorldCv();
  const PinholeIntrinsics& k = f.camera.intrinsics;
  nlohmann::json j = {{"split", split}, {"index", index}, {"file", f.file_path},
                      {"time", f.time}, {"exposure", f.exposure}, {"camera_id", f.camera_id},
                      {"width", k.width}, {"height", k.height}, {"fx", k.fx}, {"fy", k.fy},
                      {"cx", k.cx}, {"cy", k.cy}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) (c < 3 ? j["R"] : j["t"]).push_back(m(r, c));
  return j;
}

bool MapsGaussians(const LoadedRun& run) {
  return run.model.color_mode == ColorMode::kLogHdr && run.tone_mapper &&
         run.tone_mapper->pointwise();
}

// The log-HDR range the tables cover: the Gaussians' view-independent colours and the
// background, two log units wider on each side for the view-dependent and temporal terms.
std::pair<float, float> LogHdrRange(const LoadedRun& run) {
  float lo = 1e30f, hi = -1e30f;
  for (float dc : run.model.color_dc) {
    const float c = kShC0 * dc + kColorOffset;
    lo = std::min(lo, c);
    hi = std::max(hi, c);
  }
  if (run.learned_background)
    for (float b : *run.learned_background) lo = std::min(lo, b), hi = std::max(hi, b);
  if (!(hi >= lo)) lo = hi = 0;  // no Gaussians
  return {std::max(lo - 2.0f, -40.0f), std::min(hi + 2.0f, 40.0f)};
}

// The baked tables travel in the page as base64 (4/3 of their bytes): refused before baking past
// 256 MiB of floats, a page no browser opens comfortably (the defaults: under 7 MiB).
void CheckToneTableSize(const LoadedRun& run, const ViewerPageOptions& o, std::size_t exposures) {
  constexpr double kMaxBytes = 256.0 * (1 << 20);
  const int rows = std::min(run.num_times, std::max(o.max_time_rows, 1));
  const double bytes = 4.0 * 3 * rows * static_cast<double>(exposures) * o.tone_nodes;
  if (bytes > kMaxBytes)
    Fail("view: the baked tone tables would take {:.0f} MiB ({} time rows x {} exposures x {} "
         "nodes x 3 channels), over the page's {:.0f} MiB: lower --tone-nodes or "
         "--exposure-steps",
         bytes / (1 << 20), rows, exposures, o.tone_nodes, kMaxBytes / (1 << 20));
}

nlohmann::json ToneJson(const LoadedRun& run, const ViewerPageOptions& o,
                        const std::vector<float>& log_exposures) {
  CheckToneTableSize(run, o, log_exposures.size());
  const auto [x0, x1] = LogHdrRange(run);
  const ToneTables t = BakeToneTables(run.tone_mapper.get(), x0, x1, o.tone_nodes, run.num_times,
                                      o.max_time_rows, log_exposures);
  return {{"x0", t.x0}, {"x1", t.x1}, {"nodes", t.nodes}, {"time_indices", t.time_indices},
          {"log_exposures", t.log_exposures},
          {"values", Base64(t.values.data(), t.values.size() * sizeof(float))}};
}

std::pair<double, double> ExposureRange(const Dataset& d) {
  double lo = 1e300, hi = 0;
  for (const Frame* f : d.AllFrames()) lo = std::min(lo, f->exposure), hi = std::max(hi, f->exposure);
  if (!(hi > 0)) return {1.0, 1.0};
  return {lo, hi};
}

nlohmann::json PageData(const LoadedRun& run, const ViewerPageOptions& o) {
  const auto [e_lo, e_hi] = ExposureRange(run.dataset);
  // The slider reaches two stops beyond the scene's exposures; the tables cover the same range.
  const double s_lo = e_lo / 4, s_hi = e_hi * 4;
  std::vector<float> log_exposures;
  const int steps = std::max(o.exposure_steps, 2);
  for (int k = 0; k < steps; ++k)
    log_exposures.push_back(static_cast<float>(std::log(s_lo) + (std::log(s_hi) - std::log(s_lo)) * k / (steps - 1)));
  nlohmann::json j;
  j["title"] = o.title;
  j["method"] = run.MethodName();
  j["colour"] = run.model.color_mode == ColorMode::kLogHdr ? "log-hdr" : "ldr";
  j["ldr_note"] = ViewerLdrNote(run);
  j["num_times"] = run.num_times;
  j["exposure"] = {{"min", e_lo}, {"max", e_hi}, {"slider_min", s_lo}, {"slider_max", s_hi},
                   {"median", MedianExposure(run.dataset)}};
  j["tone"] = MapsGaussians(run) ? ToneJson(run, o, log_exposures) : nlohmann::json();
  j["hdr_log_scale"] = run.hdr_head.empty() ? 0.0f : run.hdr_head.log_scale;
  j["cameras"] = nlohmann::json::array();
  for (const auto& [split, frames] : {std::pair{"train", &run.dataset.train},
                                      std::pair{"test", &run.dataset.test},
                                      std::pair{"val", &run.dataset.val}}) {
    for (std::size_t i = 0; i < frames->size(); ++i)
      j["cameras"].push_back(CameraJson((*frames)[i], split, static_cast<int>(i)));
  }
  return j;
}

// Replaces the one `marker` in `page` by `text`; a missing marker is a broken asset (a bug).
void Fill(std::string* page, const std::string& marker, const std::string& text) {
  const std::size_t at = page->find(marker);
  HDR4D_CHECK(at != std::string::npos);
  page->replace(at, marker.size(), text);
}

}  // namespace

std::string ViewerLdrNote(const LoadedRun& run) {
  if (run.model.color_mode == ColorMode::kLdr)
    return "LDR colours (no exposure, no HDR): the LDR mode shows the model's colours";
  if (!run.tone_mapper)
    return "no tone mapper: HDR mode only (exposure x HDR, sRGB)";
  if (!run.tone_mapper->pointwise())
    return fmt::format("the '{}' tone mapper maps whole images; HDR mode only",
                       run.tone_mapper->config().kind);
  std::string note = fmt::format(
      "LDR: the Gaussians' log-HDR colours through the run's '{}' tone curves at the time and "
      "exposure (baked tables), then blended",
      run.tone_mapper->config().kind);
  if (run.resolved.final_ldr_from_pixels)
    note += " (this run's own LDR output maps the blended HDR image instead: expect differences)";
  return note;
}

std::string ViewerPageHtml(const LoadedRun& run, const ViewerPageOptions& options) {
  if (run.model.channels != 3)
    Fail("view: the viewer shows RGB; this model has {} channels", run.model.channels);
  Gaussian4dPlyInfo info;
  const auto [e_lo, e_hi] = ExposureRange(run.dataset);
  info.exposure_min = e_lo;
  info.exposure_max = e_hi;
  if (run.learned_background) info.learned_background = *run.learned_background;
  info.background = run.background;
  info.head = run.hdr_head.empty() ? nullptr : &run.hdr_head;
  const std::string ply = Gaussian4dPlyBytes(run.model, info);
  std::string data = PageData(run, options).dump();
  // Inside <script>, "</" could end the element: JSON lets "/" be escaped.
  for (std::size_t at = 0; (at = data.find("</", at)) != std::string::npos; at += 3)
    data.replace(at, 2, "<\\/");
  std::string page(kViewerHtml);
  Fill(&page, "/*HDR4D_VIEWER_CSS*/", std::string(kViewerCss));
  // The scripts in the order they build on each other (each names what it uses).
  std::string js;
  for (std::string_view part : {kViewerMathsJs, kViewerSplatsJs, kViewerGlJs, kViewerUiJs, kViewerOrbitJs})
    js.append(part).append("\n");
  Fill(&page, "/*HDR4D_VIEWER_JS*/", js);
  Fill(&page, "HDR4D_VIEWER_DATA", data);
  Fill(&page, "HDR4D_VIEWER_PLY", Base64(ply.data(), ply.size()));
  return page;
}

}  // namespace hdr4d::method
