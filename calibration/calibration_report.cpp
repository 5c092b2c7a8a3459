#include "calibration/calibration_report.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/files/json_util.h"

namespace hdr4d {

namespace {

void AppendRigTimePoints(const RigTimeReport& r, std::string& md, nlohmann::json& doc) {
  md += fmt::format(
      "Rig-time points (the rig cameras' own sequence, one mid bracket per camera and time): {} of {} times "
      "matched; {} cross-checked matches, {} within the Sampson bound, {} tracks; {} new points and {} existing "
      "points seen by more cameras, {} observations added to the refinement ({} repeats of existing observations "
      "left out; rejected: {} behind a camera, {} over the reprojection bound, {} under the triangulation angle). "
      "Their reprojection RMS: {:.3f} px at triangulation, {:.3f} px after the refinement. The cameras' RMS "
      "above is over COLMAP's observations; their observation counts include these.\n\n",
      r.times_used, r.times, r.matches, r.matches_kept, r.tracks, r.points_added, r.points_extended,
      r.observations_added, r.repeats, r.rejected_cheirality, r.rejected_reprojection, r.rejected_angle,
      r.rms_before, r.rms_after);
  doc["rig_time_points"] = {{"times", r.times},
                            {"times_used", r.times_used},
                            {"matches", r.matches},
                            {"matches_kept", r.matches_kept},
                            {"tracks", r.tracks},
                            {"points_added", r.points_added},
                            {"points_extended", r.points_extended},
                            {"observations_added", r.observations_added},
                            {"repeats", r.repeats},
                            {"rejected_cheirality", r.rejected_cheirality},
                            {"rejected_reprojection", r.rejected_reprojection},
                            {"rejected_angle", r.rejected_angle},
                            {"rms_before", r.rms_before},
                            {"rms_after", r.rms_after}};
}

void AppendFocalStarts(const FocalStartReport& r, std::string& md, nlohmann::json& doc) {
  md += "Focal restarts (the refinement of the model kept, again from COLMAP's poses and these scalings of its "
        "focal lengths; the least robust cost kept):\n\n| start | focal after (px) | robust cost | RMS (px) | kept "
        "|\n|---|---|---|---|---|\n";
  md += fmt::format("| model selection's own | {:.2f} | {:.3f} | | {} |\n", r.selection_focal, r.selection_cost,
                    r.kept < 0 ? "yes" : "");
  doc["focal_starts_selection"] = {{"focal", r.selection_focal}, {"cost", r.selection_cost}, {"kept", r.kept < 0}};
  for (std::size_t i = 0; i < r.starts.size(); ++i) {
    const FocalStart& s = r.starts[i];
    const bool kept = static_cast<int>(i) == r.kept;
    md += fmt::format("| x{:.2f} | {:.2f} | {:.3f} | {:.4f} | {} |\n", s.scale, s.focal, s.cost, s.rms,
                      kept ? "yes" : "");
    doc["focal_starts"].push_back({{"scale", s.scale}, {"focal", s.focal}, {"cost", s.cost}, {"rms", s.rms},
                                   {"kept", kept}});
  }
  md += "\n";
}

void AppendGeometry(const CalibrationRecord& record, std::string& md, nlohmann::json& doc) {
  const Rig& rig = *record.rig;
  md += fmt::format("## Geometry{}\n\nSparse model: {}. Intrinsics: {}. {} extra image(s) helped "
                    "the reconstruction and were dropped. Scene normalised: centre ({:.4g}, {:.4g}, "
                    "{:.4g}), scale {:.4g}; metric scale: {}. Refinement: {} iterations.\n\n",
                    record.geometry_run ? "" : " (from rig.json of an earlier run)",
                    rig.model_source, rig.intrinsics_source, rig.extra_images_registered,
                    rig.centre.x(), rig.centre.y(), rig.centre.z(), rig.scale,
                    rig.metres_per_unit > 0 ? fmt::format("1 unit = {:.4g} m (checkerboard)", rig.metres_per_unit)
                                            : std::string("unknown (no board seen by two cameras)"),
                    rig.refinement_iterations);
  doc["metres_per_unit"] = rig.metres_per_unit;
  doc["intrinsics_source"] = rig.intrinsics_source;
  md += "| camera | static images registered | observations | reprojection RMS before (px) | "
        "after (px) | focal (px) | k1 | k2 | distortion kept (BIC gain over none) | max distortion (px) | undistorted |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const RigCamera& c : rig.cameras) {
    md += fmt::format("| {} | {} | {} | {:.3f} | {:.3f} | {:.2f} | {:.4f} | {:.4f} | {} ({:.1f}) | {:.2f} | {} |\n",
                      c.name, c.static_images_registered, c.observations, c.rms_before,
                      c.rms_after, c.intrinsics.f, c.intrinsics.k1, c.intrinsics.k2,
                      !c.distortion_kept ? "no" : c.distortion_terms == 1 ? "k1" : "k1, k2",
                      c.distortion_score, c.max_distortion_pixels,
                      c.undistort ? "yes" : "no");
    doc["cameras"].push_back({{"name", c.name}, {"rms_before", c.rms_before},
                              {"rms_after", c.rms_after}, {"focal", c.intrinsics.f},
                              {"distortion_kept", c.distortion_kept}, {"distortion_terms", c.distortion_terms},
                              {"focal_shared", c.focal_shared},
                              {"distortion_score", c.distortion_score},
                              {"undistorted", c.undistort}});
  }
  md += fmt::format("\n{} points in point3d.ply.\n\n", rig.points.size());
  if (rig.focal_starts) AppendFocalStarts(*rig.focal_starts, md, doc);
  if (rig.rig_time) AppendRigTimePoints(*rig.rig_time, md, doc);
}

void AppendCameraAgreement(const CalibrationRecord& record, std::string& md, nlohmann::json& doc) {
  const CameraGains& g = *record.gains;
  md += fmt::format("### Camera agreement\n\nOn {} sparse points seen by two or more cameras ({}; {}), "
                    "the cameras' HDR differed from the points' mean by {:.1f}% (median) "
                    "before the per-camera gains and {:.1f}% after{}. Those figures include the texture's "
                    "scatter between where each camera samples a point (3-5% on textured walls for a perfect "
                    "calibration); what measures the gains: estimated on every other point, each camera's "
                    "median bias on the rest is at most {:.1f}%. Vignetting (radiance x 1 - v (r / r_corner)^2) is "
                    "estimated on the same points; where it is divided out (--vignetting auto: v >= {:g} and >= {:g} "
                    "standard errors) the "
                    "gains are solved after it, and the camera's HDR and brackets are corrected.\n\n"
                    "| camera | gain R | G | B | vignetting v | standard error | divided out |\n|---|---|---|---|---|---|---|\n",
                    g.points_used,
                    g.footprint_pixels > 0
                        ? fmt::format("each camera averaging the same patch of surface, {:g} px in the camera "
                                      "that sees it smallest", g.footprint_pixels)
                        : std::string("a 3x3 window in every camera"),
                    g.from_static_images ? "their static images, in the first frame's HDR units"
                                         : "the first frame's fused HDR",
                    100 * g.disagreement_before, 100 * g.disagreement_after,
                    record.gains_applied ? " (applied to hdr/, the mean gain folded into `exposures`)"
                                         : " (not applied: --no-gain-correction)",
                    100 * g.held_out_bias, kVignettingApplyFrom, kVignettingSignificance);
  const auto vignetting = [](const std::vector<double>& v, std::size_t c) {
    return c < v.size() ? fmt::format("{:.3f}", v[c]) : std::string("-");
  };
  for (std::size_t c = 0; c < g.gain.size() && c < record.rig->cameras.size(); ++c)
    md += fmt::format("| {} | {:.4f} | {:.4f} | {:.4f} | {} | {} | {} |\n", record.rig->cameras[c].name, g.gain[c][0],
                      g.gain[c][1], g.gain[c][2], vignetting(g.vignetting, c), vignetting(g.vignetting_error, c),
                      vignetting(g.vignetting_applied, c));
  md += "\n";
  doc["camera_agreement"] = {{"points", g.points_used},
                             {"sampled_in", g.from_static_images ? "static images" : "first frame"},
                             {"disagreement_before", g.disagreement_before},
                             {"disagreement_after", g.disagreement_after},
                             {"held_out_bias", g.held_out_bias},
                             {"footprint_pixels", g.footprint_pixels},
                             {"vignetting_estimate", g.vignetting},
                             {"vignetting_standard_error", g.vignetting_error},
                             {"vignetting_applied", g.vignetting_applied},
                             {"gains", g.gain}};
}

void AppendRadiometry(const CalibrationRecord& record, std::string& md, nlohmann::json& doc) {
  md += fmt::format("## Radiometry\n\nResponse: {}, {} (the cameras' own curves differ by {:.3f} "
                    "RMS in log exposure over codes 32-223; above 0.05, or with --per-camera-response, "
                    "each camera is fused with its own).\n\n![response](response.png)\n\n",
                    record.response_method,
                    record.per_camera_response ? "one curve per channel per camera in response_<camera>.csv "
                                                 "(the rig's joint curve in response.csv)"
                                               : "one curve per channel shared by every camera, in response.csv",
                    record.response_spread);
  if (!record.frames.empty() && !record.frames.front().noise.empty()) {
    md += fmt::format("Fusion weights (inverse variance of each bracket's radiance estimate) of {} frame "
                      "{}: black level / read noise / saturation per channel (codes):",
                      record.frames.front().camera, record.frames.front().frame);
    for (const ChannelNoise& n : record.frames.front().noise)
      md += fmt::format(" {:.1f} / {:.2f} / {:.0f}{};", n.black, n.read_sigma, n.saturation,
                        n.floor_found ? "" : " (no black floor seen)");
    md += "\n\n";
  }
  doc["per_camera_response"] = record.per_camera_response;
  doc["response_spread"] = record.response_spread;
  if (record.gains && record.rig) AppendCameraAgreement(record, md, doc);
  md += "| camera | frame | dynamic range (stops) | moving pixels (best-exposed bracket only) | "
        "reference bracket |\n|---|---|---|---|---|\n";
  for (const FrameRecord& f : record.frames) {
    md += fmt::format("| {} | {} | {:.2f} | {:.2f}% | {} |\n", f.camera, f.frame,
                      f.dynamic_range_stops, 100 * f.motion_fraction, f.reference_bracket);
    doc["frames"].push_back({{"camera", f.camera}, {"frame", f.frame},
                             {"dynamic_range_stops", f.dynamic_range_stops},
                             {"motion_fraction", f.motion_fraction}});
  }
  md += "\n";
}

}  // namespace

void WriteCalibrationReport(const std::filesystem::path& folder, const CalibrationRecord& record) {
  std::string md = "# Calibration report\n\n";
  nlohmann::json doc;
  if (record.rig) AppendGeometry(record, md, doc);
  if (!record.response_method.empty()) AppendRadiometry(record, md, doc);
  if (!record.test_camera.empty())
    md += fmt::format("Dataset: camera {} is the test split, the others train.\n\n", record.test_camera);
  if (!record.warnings.empty()) {
    md += "## Warnings\n\n";
    for (const std::string& w : record.warnings) md += "- " + w + "\n";
    md += "\n";
  }
  md += fmt::format("## Time\n\ngeometry {:.1f} s, radiometry {:.1f} s\n", record.seconds_geometry,
                    record.seconds_radiometry);
  doc["seconds"] = {{"geometry", record.seconds_geometry}, {"radiometry", record.seconds_radiometry}};
  doc["warnings"] = record.warnings;
  doc["response_method"] = record.response_method;
  WriteTextFileAtomic(folder / "report.md", md);
  WriteJsonFile(folder / "calibration.json", doc);
}

}  // namespace hdr4d
