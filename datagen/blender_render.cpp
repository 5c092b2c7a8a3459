#include "datagen/blender_render.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <fstream>
#include <regex>

#include "core/util/error.h"
#include "core/files/json_util.h"
#include "core/util/progress.h"
#include "datagen/blender_process.h"

namespace hdr4d::datagen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What the one-line message quotes: the last Python exception in the log ("ValueError: ..."),
// else the last line mentioning an error (Blender's own "Error: ..."), else the last line.
std::string LastErrorLine(const std::deque<std::string>& tail) {
  static const std::regex kException(R"(^\s*[A-Za-z_][\w.]*(Error|Exception)\b.*)");
  for (auto it = tail.rbegin(); it != tail.rend(); ++it) {
    if (std::regex_match(*it, kException)) return *it;
  }
  for (auto it = tail.rbegin(); it != tail.rend(); ++it) {
    if (it->find("Error") != std::string::npos) return *it;
  }
  for (auto it = tail.rbegin(); it != tail.rend(); ++it) {
    if (it->find_first_not_of(" \t\r") != std::string::npos) return *it;
  }
  return "(no output)";
}

// Runs Blender on the plan in `staging`; returns its wall time.
double RunBlender(const ScenePreset& preset,
                  const std::vector<PlannedRender>& renders,
                  const BlenderSettings& settings,
                  const fs::path& staging) {
  const fs::path blender = FindBlender(settings.blender);
  const fs::path scripts = FindScriptsDir(settings.scripts_dir);
  const std::vector<std::string> argv = {blender.string(),
                                         "-b",
                                         "--factory-startup",
                                         "--python-exit-code",
                                         "1",
                                         "-P",
                                         (scripts / kRenderScript).string(),
                                         "--",
                                         "--plan",
                                         (staging / kPlanFile).string()};
  const fs::path log_path = staging / kLogFile;
  std::ofstream log(log_path);
  if (!log) Fail("{}: cannot write the Blender log", log_path.string());
  std::string command;
  for (const std::string& a : argv) command += (command.empty() ? "" : " ") + a;
  log << "# " << command << "\n";

  const int total = static_cast<int>(renders.size());
  Progress progress(fmt::format("datagen {}", preset.scene), total, settings.show_progress);
  int started = 0;  // the frame Blender is working on (1-based), 0 before the first
  std::deque<std::string> tail;
  const auto start = std::chrono::steady_clock::now();
  const ProcessResult result = RunProcess(argv, [&](const std::string& line) {
    log << line << '\n';
    tail.push_back(line);
    if (tail.size() > 40) tail.pop_front();
    int i = 0, n = 0;
    if (std::sscanf(line.c_str(), "HDR4D_RENDERING %d %d", &i, &n) == 2) {
      started = i;
    } else if (std::sscanf(line.c_str(), "HDR4D_RENDERED %d %d", &i, &n) == 2) {
      progress.Advance(1, renders[std::clamp(i - 1, 0, total - 1)].hdr_file);
    }
  });
  log.flush();
  progress.Finish();
  if (!result.ok()) {
    const std::string where =
        started == 0 ? "while building the scene"
                     : fmt::format("while rendering frame {}/{} ({})", started, total,
                                   renders[std::clamp(started - 1, 0, total - 1)].hdr_file);
    Fail("datagen: scene '{}': Blender failed ({}) {}: {}; full log: {}", preset.scene,
         result.Describe(), where, LastErrorLine(tail), log_path.string());
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// render_info.json, checked against the plan: one entry per planned render, in order.
json ReadRenderInfo(const ScenePreset& preset,
                    const std::vector<PlannedRender>& renders,
                    const fs::path& staging) {
  const fs::path path = staging / kInfoFile;
  if (!fs::exists(path)) {
    Fail("datagen: scene '{}': {}: Blender exited without writing it (log: {})", preset.scene,
         path.string(), (staging / kLogFile).string());
  }
  const json info = ReadJsonFile(path);
  const auto bad = [&](const std::string& what) {
    Fail("datagen: scene '{}': {}: {}", preset.scene, path.string(), what);
  };
  if (!info.is_object() || !info.contains("renders") || !info["renders"].is_array())
    bad("key 'renders' missing or not an array");
  if (!info.contains("camera_angle_x") || !info["camera_angle_x"].is_number())
    bad("key 'camera_angle_x' missing or not a number");
  if (!info.contains("blender_version") || !info["blender_version"].is_string())
    bad("key 'blender_version' missing or not a string");
  if (info["renders"].size() != renders.size())
    bad(fmt::format("{} renders reported, {} planned", info["renders"].size(), renders.size()));
  for (std::size_t i = 0; i < renders.size(); ++i) {
    const json& r = info["renders"][i];
    if (!r.is_object() || r.value("file", "") != renders[i].hdr_file)
      bad(fmt::format("render {} is not {}", i, renders[i].hdr_file));
    const json& m = r.value("transform_matrix", json());
    bool ok = m.is_array() && m.size() == 4;
    for (std::size_t row = 0; ok && row < 4; ++row) {
      ok = m[row].is_array() && m[row].size() == 4;
      for (std::size_t c = 0; ok && c < 4; ++c) ok = m[row][c].is_number();
    }
    if (!ok) bad(fmt::format("render {}: transform_matrix is not a 4x4 array of numbers", i));
  }
  return info;
}

}  // namespace

json RenderPlanJson(const ScenePreset& preset,
                    const std::vector<PlannedRender>& renders,
                    const BlenderSettings& settings) {
  json items = json::array();
  for (const PlannedRender& r : renders) {
    items.push_back({{"file", r.hdr_file},
                     {"camera_id", r.camera_id},
                     {"time_index", r.time_index},
                     {"time", r.time},
                     {"split", SplitName(r.split)}});
    if (r.still) items.back()["static"] = true;  // only then, so other plans keep their bytes
  }
  json plan = {{"format", "hdr4d-datagen-plan"}, {"format_version", kPlanFormatVersion},
          {"scene", preset.scene},          {"preset", preset.preset},
          {"seed", settings.seed},          {"rig", RigName(preset.rig)},
          {"cameras", preset.cameras},      {"held_out_cameras", preset.held_out_cameras},
          {"width", preset.width},
          {"height", preset.height},        {"samples", preset.samples},
          {"threads", settings.threads},    {"camera_angle_x", preset.camera_angle_x},
          {"points", preset.points},        {"point_times", PointSampleTimes(preset)},
          {"points_file", kPointsFile},
          {"info_file", kInfoFile},         {"renders", items}};
  if (preset.layout != "scene") plan["layout"] = preset.layout;
  return plan;
}

BlenderRender RenderWithBlender(const ScenePreset& preset,
                                const std::vector<PlannedRender>& renders,
                                const BlenderSettings& settings,
                                const fs::path& staging) {
  WriteJsonFile(staging / kPlanFile, RenderPlanJson(preset, renders, settings));
  BlenderRender out;
  out.seconds = RunBlender(preset, renders, settings, staging);
  out.info = ReadRenderInfo(preset, renders, staging);
  return out;
}

namespace {

// The first top-level key where two plans differ, "" when they agree; the Cycles thread count
// changes no pixel (datagen's own determinism test), so it is left out.
std::string FirstDifference(json a, json b) {
  a.erase("threads");
  b.erase("threads");
  if (a == b) return "";
  for (const auto& [key, value] : a.items())
    if (!b.contains(key) || b[key] != value) return key;
  for (const auto& [key, value] : b.items())
    if (!a.contains(key)) return key;
  return "?";
}

}  // namespace

std::optional<BlenderRender> ReuseRenders(const ScenePreset& preset,
                                          const std::vector<PlannedRender>& renders,
                                          const BlenderSettings& settings,
                                          const fs::path& source,
                                          const fs::path& staging,
                                          std::string* why) {
  const fs::path plan_file = source / kPlanFile;
  if (!fs::exists(plan_file) || !fs::exists(source / kInfoFile) ||
      !fs::exists(source / "point3d.ply")) {
    *why = fmt::format("{} holds no finished dataset of datagen", source.string());
    return std::nullopt;
  }
  const json plan = RenderPlanJson(preset, renders, settings);
  json theirs;
  try {
    theirs = ReadJsonFile(plan_file);
  } catch (const Error& e) {
    *why = e.what();
    return std::nullopt;
  }
  if (const std::string key = FirstDifference(plan, theirs); !key.empty()) {
    *why = fmt::format("{} was rendered from another plan ('{}' differs)", plan_file.string(), key);
    return std::nullopt;
  }
  for (const PlannedRender& r : renders) {
    if (!fs::exists(source / r.hdr_file)) {
      *why = fmt::format("{} is missing", (source / r.hdr_file).string());
      return std::nullopt;
    }
  }
  for (const PlannedRender& r : renders) {
    fs::create_directories((staging / r.hdr_file).parent_path());
    fs::copy_file(source / r.hdr_file, staging / r.hdr_file, fs::copy_options::overwrite_existing);
  }
  fs::copy_file(source / kInfoFile, staging / kInfoFile, fs::copy_options::overwrite_existing);
  WriteJsonFile(staging / kPlanFile, plan);
  std::ofstream log(staging / kLogFile);
  log << fmt::format("hdr4d datagen: the renders of {} reused (--reuse-renders); its log:\n",
                     source.string());
  if (std::ifstream old(source / kLogFile); old) log << old.rdbuf();
  BlenderRender out;
  out.info = ReadRenderInfo(preset, renders, staging);
  return out;
}

}  // namespace hdr4d::datagen
