#include "benchmark/run_record.h"

#include <cmath>
#include <ctime>
#include <limits>
#include <optional>
#include <type_traits>
#include <tuple>

#include "benchmark/names.h"
#include "core/files/json_util.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

// JSON has no inf/NaN: +inf (a PSNR of identical images) is written as the string "inf",
// NaN (unknown) as null.
nlohmann::json Number(double v) {
  if (std::isnan(v)) return nullptr;
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return v;
}

double ToNumber(const nlohmann::json& j, const std::string& source, const std::string& key) {
  if (j.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (j.is_number()) return j.get<double>();
  if (j.is_string() && (j == "inf" || j == "-inf"))
    return j == "inf" ? std::numeric_limits<double>::infinity()
                      : -std::numeric_limits<double>::infinity();
  Fail("{}: key '{}': expected a number, got {}", source, key, j.dump());
}

template <typename T>
T Get(const nlohmann::json& j, const char* key, const std::string& source) {
  if (!j.is_object()) Fail("{}: expected a JSON object, got {}", source, JsonPreview(j));
  if (!j.contains(key)) Fail("{}: key '{}' missing", source, key);
  if constexpr (std::is_same_v<T, std::int64_t>) return JsonInteger(j.at(key), source, key);
  try {
    return j.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    Fail("{}: key '{}' has the wrong type ({})", source, key, JsonPreview(j.at(key)));
  }
}

// An optional key: `fallback` when absent or null, else of type T or an error naming the key (a
// raw "[json.exception.type_error.302]" named neither, issue 51, case 24).
template <typename T>
T Optional(const nlohmann::json& j, const char* key, T fallback, const std::string& source) {
  if (!j.is_object()) Fail("{}: expected a JSON object, got {}", source, JsonPreview(j));
  if (!j.contains(key) || j.at(key).is_null()) return fallback;
  return Get<T>(j, key, source);
}

// A JSON value that must be an object or an array, named by its key when it is not.
const nlohmann::json& Container(const nlohmann::json& j, bool object, const char* key,
                                const std::string& source) {
  if (object ? !j.is_object() : !j.is_array())
    Fail("{}: key '{}' must be a JSON {}, got {}", source, key, object ? "object" : "array",
         JsonPreview(j));
  return j;
}

}  // namespace

std::int64_t JsonInteger(const nlohmann::json& value, const std::string& source,
                         const std::string& key, std::int64_t min) {
  std::optional<std::int64_t> v;
  if (value.is_number_unsigned()) {
    if (value.get<std::uint64_t>() <= std::numeric_limits<std::int64_t>::max())
      v = static_cast<std::int64_t>(value.get<std::uint64_t>());
  } else if (value.is_number_integer()) {
    v = value.get<std::int64_t>();
  } else if (value.is_number_float()) {
    const double d = value.get<double>();
    // [-2^63, 2^63): the doubles that convert to an int64 exactly.
    if (d == std::trunc(d) && d >= -0x1p63 && d < 0x1p63) v = static_cast<std::int64_t>(d);
  }
  if (!v)
    Fail("{}: key '{}' must be an integer (at most {}), got {}", source, key,
         std::numeric_limits<std::int64_t>::max(), JsonPreview(value));
  if (*v < min) Fail("{}: key '{}' must be at least {}, got {}", source, key, min, *v);
  return *v;
}

nlohmann::json RunLabel::ToJson() const {
  return {{"suite", suite}, {"method", method}, {"scene", scene}, {"supervision", supervision},
          {"seed", seed},   {"budget", budget}, {"variant", variant}};
}

RunLabel RunLabel::FromJson(const nlohmann::json& j, const std::string& source) {
  RunLabel l;
  l.suite = Get<std::string>(j, "suite", source);
  l.method = Get<std::string>(j, "method", source);
  l.scene = Get<std::string>(j, "scene", source);
  l.supervision = Get<std::string>(j, "supervision", source);
  l.seed = Get<std::int64_t>(j, "seed", source);
  l.budget = Get<std::string>(j, "budget", source);
  l.variant = Get<std::string>(j, "variant", source);
  // Labels name rows, files and folders: names only (issue 51, case 9); "" is the default variant.
  for (auto [key, value] : {std::pair{"suite", &l.suite}, std::pair{"method", &l.method},
                            std::pair{"scene", &l.scene}, std::pair{"supervision", &l.supervision},
                            std::pair{"budget", &l.budget}, std::pair{"variant", &l.variant}}) {
    if (value != &l.variant || !value->empty()) RequireName(*value, source + ": key '" + key + "'");
  }
  return l;
}

bool RunLabel::operator<(const RunLabel& o) const {
  return std::tie(suite, method, scene, supervision, seed, budget, variant) <
         std::tie(o.suite, o.method, o.scene, o.supervision, o.seed, o.budget, o.variant);
}

nlohmann::json RunRecord::ToJson() const {
  nlohmann::json j = {{"id", id},
                      {"source", source},
                      {"status", status},
                      {"error", error},
                      {"config", config},
                      {"code_version", code_version},
                      {"git_describe", git_describe},
                      {"machine", machine},
                      {"data_checksum", data_checksum},
                      {"scene_dir", scene_dir},
                      {"run_dir", run_dir},
                      {"train_seconds", Number(train_seconds)},
                      {"render_fps", Number(render_fps)},
                      {"peak_rss_mb", Number(peak_rss_mb)},
                      {"wall_seconds", Number(wall_seconds)},
                      {"iterations", iterations},
                      {"gaussians", gaussians},
                      {"started_at", started_at},
                      {"finished_at", finished_at}};
  j["labels"] = nlohmann::json::array();
  for (const RunLabel& l : labels) j["labels"].push_back(l.ToJson());
  j["frames"] = nlohmann::json::array();
  for (const FrameResult& f : frames) {
    nlohmann::json m = nlohmann::json::object(), s = nlohmann::json::object();
    for (const auto& [k, v] : f.metrics) m[k] = Number(v);
    for (const auto& [k, v] : f.stats) s[k] = Number(v);
    j["frames"].push_back({{"frame", f.frame},
                           {"time", f.time},
                           {"camera_id", f.camera_id},
                           {"exposure", f.exposure},
                           {"metrics", m},
                           {"stats", s}});
  }
  j["series"] = nlohmann::json::object();
  for (const auto& [name, points] : series) {
    nlohmann::json p = nlohmann::json::array();
    for (const auto& [x, y] : points) p.push_back({Number(x), Number(y)});
    j["series"][name] = p;
  }
  return j;
}

RunRecord RunRecord::FromJson(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) Fail("{}: a run record must be a JSON object", source);
  RunRecord r;
  r.id = Get<std::string>(j, "id", source);
  if (r.id.empty()) Fail("{}: key 'id' is empty", source);
  r.source = Get<std::string>(j, "source", source);
  r.status = Get<std::string>(j, "status", source);
  if (r.status != "ok" && r.status != "failed")
    Fail("{}: key 'status' must be ok or failed, not '{}'", source, r.status);
  r.error = Get<std::string>(j, "error", source);
  r.config = Container(Optional(j, "config", nlohmann::json::object(), source), true, "config", source);
  r.code_version = Get<std::string>(j, "code_version", source);
  r.git_describe = Optional<std::string>(j, "git_describe", "", source);
  r.machine =
      Container(Optional(j, "machine", nlohmann::json::object(), source), true, "machine", source);
  r.data_checksum = Get<std::string>(j, "data_checksum", source);
  r.scene_dir = Optional<std::string>(j, "scene_dir", "", source);
  r.run_dir = Optional<std::string>(j, "run_dir", "", source);
  for (auto [key, field] : {std::pair{"train_seconds", &r.train_seconds},
                            std::pair{"render_fps", &r.render_fps},
                            std::pair{"peak_rss_mb", &r.peak_rss_mb},
                            std::pair{"wall_seconds", &r.wall_seconds}}) {
    *field = ToNumber(j.value(key, nlohmann::json()), source, key);
  }
  r.iterations = Optional<std::int64_t>(j, "iterations", -1, source);
  r.gaussians = Optional<std::int64_t>(j, "gaussians", -1, source);
  r.started_at = Optional<std::string>(j, "started_at", "", source);
  r.finished_at = Optional<std::string>(j, "finished_at", "", source);
  // Named copies: a range over a reference into a temporary would outlive it.
  const nlohmann::json labels = Get<nlohmann::json>(j, "labels", source);
  for (const nlohmann::json& l : Container(labels, false, "labels", source))
    r.labels.push_back(RunLabel::FromJson(l, source + ": labels"));
  if (r.labels.empty()) Fail("{}: key 'labels' is empty (a run must appear somewhere)", source);
  const nlohmann::json frames = Get<nlohmann::json>(j, "frames", source);
  for (const nlohmann::json& f : Container(frames, false, "frames", source)) {
    FrameResult fr;
    const std::string where = source + ": frames";
    fr.frame = Get<std::string>(f, "frame", where);
    fr.time = Get<double>(f, "time", where);
    fr.camera_id = Optional<std::int64_t>(f, "camera_id", -1, where);
    fr.exposure = Optional(f, "exposure", 0.0, where);
    // Named copies: items() of a temporary would outlive it.
    const nlohmann::json metrics = Optional(f, "metrics", nlohmann::json::object(), where);
    const nlohmann::json stats = Optional(f, "stats", nlohmann::json::object(), where);
    Container(metrics, true, "metrics", where);
    Container(stats, true, "stats", where);
    for (const auto& [k, v] : metrics.items()) fr.metrics[k] = ToNumber(v, where + " " + fr.frame, k);
    for (const auto& [k, v] : stats.items()) fr.stats[k] = ToNumber(v, where + " " + fr.frame, k);
    r.frames.push_back(std::move(fr));
  }
  const nlohmann::json series = Optional(j, "series", nlohmann::json::object(), source);
  Container(series, true, "series", source);
  for (const auto& [name, points] : series.items()) {
    Series& s = r.series[name];
    for (const nlohmann::json& p : Container(points, false, name.c_str(), source)) {
      if (!p.is_array() || p.size() != 2) Fail("{}: series '{}': points must be [x, y]", source, name);
      s.emplace_back(ToNumber(p[0], source, name), ToNumber(p[1], source, name));
    }
  }
  return r;
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

void ThinSeries(RunRecord* record, int points) {
  HDR4D_CHECK(points >= 2);
  for (auto& [name, series] : record->series) {
    const std::size_t n = series.size();
    if (n <= static_cast<std::size_t>(points)) continue;
    Series kept;
    for (int k = 0; k < points; ++k) {
      // Index round(k (n - 1) / (points - 1)): 0 and n - 1 included, strictly increasing.
      const std::size_t i = (static_cast<std::size_t>(k) * (n - 1) + (points - 1) / 2) /
                            static_cast<std::size_t>(points - 1);
      kept.push_back(series[i]);
    }
    series = std::move(kept);
  }
}

}  // namespace hdr4d::bench
