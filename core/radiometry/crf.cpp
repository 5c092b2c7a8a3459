#include "core/radiometry/crf.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <string_view>

#include "core/files/file_access.h"
#include "core/files/json_util.h"
#include "core/radiometry/channel_crf.h"
#include "core/util/error.h"

namespace hdr4d {
namespace {

// x < 0 -> 0 (noise may push exposures below zero); NaN stays NaN.
inline double ClampExposure(double x) { return x < 0.0 ? 0.0 : x; }

// Parses the whole of `text` as a double; false if anything is left over or nothing parsed.
bool ParseDouble(std::string_view text, double& out) {
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, out);
  return ec == std::errc() && ptr == end;
}

std::string_view Trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// Checks table nodes; `where(i)` names node i in messages (a CSV line, or a node index).
void CheckNodes(const std::vector<double>& x,
                const std::vector<double>& y,
                const std::function<std::string(std::size_t)>& where) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      Fail("{}: non-finite node (x = {}, y = {})", where(i), x[i], y[i]);
    }
    if (x[i] < 0) Fail("{}: x = {} is negative; exposures are >= 0", where(i), x[i]);
    if (y[i] < 0 || y[i] > 1) Fail("{}: y = {} is outside [0, 1]", where(i), y[i]);
    if (i == 0) {
      if (x[0] == 0 && y[0] != 0)
        Fail("{}: the response at x = 0 must be 0, got y = {}", where(0), y[0]);
      continue;
    }
    if (!(x[i] > x[i - 1])) {
      Fail("{}: x = {} does not increase (previous x = {}); x must increase strictly", where(i),
           x[i], x[i - 1]);
    }
    if (y[i] < y[i - 1]) {
      Fail("{}: y = {} is below the previous y = {}; a response must be non-decreasing", where(i),
           y[i], y[i - 1]);
    }
  }
  if (y.back() != 1.0) {
    Fail("{}: the table ends at y = {}; its last node must reach y = 1 (the saturation point)",
         where(x.size() - 1), y.back());
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Crf

double Crf::Derivative(double x) const {
  x = ClampExposure(x);
  const double h = 1e-6 * std::max(x, 1e-6);
  if (x >= h) return (Apply(x + h) - Apply(x - h)) / (2 * h);
  return (Apply(x + h) - Apply(x)) / h;
}

// ---------------------------------------------------------------------------------------------
// LinearCrf

double LinearCrf::Apply(double x) const { return std::min(ClampExposure(x), 1.0); }

double LinearCrf::Inverse(double y) const { return std::clamp(y, 0.0, 1.0); }

double LinearCrf::Derivative(double x) const { return ClampExposure(x) <= 1.0 ? 1.0 : 0.0; }

nlohmann::json LinearCrf::ToJson() const { return {{"model", "linear"}}; }

// ---------------------------------------------------------------------------------------------
// GammaCrf

GammaCrf::GammaCrf(double gamma) : gamma_(gamma) {
  if (!std::isfinite(gamma) || !(gamma > 0)) {
    Fail("gamma CRF: gamma must be a finite number > 0, got {}", gamma);
  }
}

double GammaCrf::Apply(double x) const {
  x = ClampExposure(x);
  if (x >= 1.0) return 1.0;
  return std::pow(x, 1.0 / gamma_);
}

double GammaCrf::Inverse(double y) const {
  if (std::isnan(y)) return y;
  return std::pow(std::clamp(y, 0.0, 1.0), gamma_);
}

double GammaCrf::Derivative(double x) const {
  x = ClampExposure(x);
  if (x > 1.0) return 0.0;
  return std::pow(x, 1.0 / gamma_ - 1.0) / gamma_;
}

std::string GammaCrf::Spec() const { return fmt::format("gamma:{}", gamma_); }

nlohmann::json GammaCrf::ToJson() const { return {{"model", "gamma"}, {"gamma", gamma_}}; }

// ---------------------------------------------------------------------------------------------
// SrgbCrf

namespace {
constexpr double kSrgbSlope = 12.92;
constexpr double kSrgbScale = 1.055;
constexpr double kSrgbOffset = 0.055;
constexpr double kSrgbPower = 2.4;
}  // namespace

double SrgbCrf::Apply(double x) const {
  x = ClampExposure(x);
  if (x <= kLinearEnd) return kSrgbSlope * x;
  if (x >= 1.0) return 1.0;
  return kSrgbScale * std::pow(x, 1.0 / kSrgbPower) - kSrgbOffset;
}

double SrgbCrf::Inverse(double y) const {
  if (std::isnan(y)) return y;
  y = std::clamp(y, 0.0, 1.0);
  if (y <= kSrgbSlope * kLinearEnd) return y / kSrgbSlope;
  if (y >= 1.0) return 1.0;
  return std::pow((y + kSrgbOffset) / kSrgbScale, kSrgbPower);
}

double SrgbCrf::Derivative(double x) const {
  x = ClampExposure(x);
  if (x <= kLinearEnd) return kSrgbSlope;
  if (x > 1.0) return 0.0;
  return kSrgbScale / kSrgbPower * std::pow(x, 1.0 / kSrgbPower - 1.0);
}

nlohmann::json SrgbCrf::ToJson() const { return {{"model", "srgb"}}; }

// ---------------------------------------------------------------------------------------------
// FilmicCrf

FilmicCrf::FilmicCrf(double contrast, double mid) : k_(contrast), m_(mid) {
  if (!std::isfinite(contrast) || !(contrast > 0)) {
    Fail("filmic CRF: contrast must be a finite number > 0, got {}", contrast);
  }
  if (!std::isfinite(mid) || !(mid > 0)) {
    Fail("filmic CRF: mid must be a finite number > 0, got {}", mid);
  }
  mk_ = std::pow(m_, k_);
  if (!(mk_ > 0) || !std::isfinite(mk_)) {
    Fail("filmic CRF: mid^contrast = {}^{} is not a positive finite number", mid, contrast);
  }
}

double FilmicCrf::Apply(double x) const {
  x = ClampExposure(x);
  if (x >= 1.0) return 1.0;
  const double xk = std::pow(x, k_);
  return (1.0 + mk_) * xk / (xk + mk_);
}

double FilmicCrf::Inverse(double y) const {
  if (std::isnan(y)) return y;
  if (y <= 0.0) return 0.0;
  if (y >= 1.0) return 1.0;
  const double s = y / (1.0 + mk_);
  return std::min(1.0, m_ * std::pow(s / (1.0 - s), 1.0 / k_));
}

double FilmicCrf::Derivative(double x) const {
  x = ClampExposure(x);
  if (x > 1.0) return 0.0;
  const double xk = std::pow(x, k_);
  const double denom = xk + mk_;
  return (1.0 + mk_) * k_ * mk_ * std::pow(x, k_ - 1.0) / (denom * denom);
}

std::string FilmicCrf::Spec() const { return fmt::format("filmic:{},{}", k_, m_); }

nlohmann::json FilmicCrf::ToJson() const {
  return {{"model", "filmic"}, {"contrast", k_}, {"mid", m_}};
}

// ---------------------------------------------------------------------------------------------
// NakaRushtonCrf

NakaRushtonCrf::NakaRushtonCrf(double half, double gamma) : k_(half), gamma_(gamma) {
  if (!std::isfinite(half) || !(half > 0)) {
    Fail("naka-rushton CRF: the half-saturation k must be a finite number > 0, got {}", half);
  }
  if (!std::isfinite(gamma) || !(gamma > 0)) {
    Fail("naka-rushton CRF: gamma must be a finite number > 0, got {}", gamma);
  }
}

double NakaRushtonCrf::Apply(double x) const {
  if (std::isnan(x)) return x;
  x = ClampExposure(x);
  if (x >= 1.0) return 1.0;
  const double s = std::pow(x, 1.0 / gamma_);
  return (1.0 + k_) * s / (s + k_);
}

double NakaRushtonCrf::Inverse(double y) const {
  if (std::isnan(y)) return y;
  if (y <= 0.0) return 0.0;
  if (y >= 1.0) return 1.0;
  const double s = k_ * y / (1.0 + k_ - y);  // 1 + k - y > k > 0
  return std::min(1.0, std::pow(s, gamma_));
}

double NakaRushtonCrf::Derivative(double x) const {
  x = ClampExposure(x);
  if (x > 1.0) return 0.0;
  if (x == 0.0) {
    if (gamma_ > 1.0) return std::numeric_limits<double>::infinity();
    return gamma_ == 1.0 ? (1.0 + k_) / k_ : 0.0;
  }
  const double s = std::pow(x, 1.0 / gamma_);
  const double ds_dx = s / (gamma_ * x);
  return (1.0 + k_) * k_ / ((s + k_) * (s + k_)) * ds_dx;
}

std::string NakaRushtonCrf::Spec() const { return fmt::format("naka-rushton:{},{}", k_, gamma_); }

nlohmann::json NakaRushtonCrf::ToJson() const {
  return {{"model", "naka-rushton"}, {"half", k_}, {"gamma", gamma_}};
}

// ---------------------------------------------------------------------------------------------
// TableCrf

TableCrf::TableCrf(std::vector<double> x, std::vector<double> y, std::string source)
    : source_(std::move(source)) {
  if (x.size() != y.size()) {
    Fail("CRF table {}: {} x values but {} y values", source_, x.size(), y.size());
  }
  if (x.empty()) Fail("CRF table {}: no nodes", source_);
  CheckNodes(x, y, [&](std::size_t i) {
    return fmt::format("CRF table {}: node {} of {}", source_, i, x.size());
  });
  if (x.front() > 0) {
    x.insert(x.begin(), 0.0);
    y.insert(y.begin(), 0.0);
  }
  x_ = std::move(x);
  y_ = std::move(y);
  for (std::size_t i = 0; i < y_.size(); ++i) {
    if (y_[i] == 1.0) {
      x_sat_ = x_[i];
      break;
    }
  }
  for (std::size_t i = 0; i + 1 < y_.size(); ++i) {
    if (y_[i] == y_[i + 1] && y_[i] > 0 && y_[i] < 1) invertible_ = false;
  }
}

std::unique_ptr<TableCrf> TableCrf::FromCodes(const std::vector<double>& x_of_code,
                                              std::string source) {
  const std::size_t n = x_of_code.size();
  if (n < 2) Fail("CRF table {}: {} code values; an inverse response needs at least 2", source, n);
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = static_cast<double>(i) / static_cast<double>(n - 1);
  return std::make_unique<TableCrf>(x_of_code, std::move(y), std::move(source));
}

namespace {

// A CSV line's fields: split by commas, or by whitespace when the line has none.
std::vector<std::string_view> SplitCsvFields(std::string_view text) {
  std::vector<std::string_view> fields;
  const bool commas = text.find(',') != std::string_view::npos;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = commas ? text.find(',', start) : text.find_first_of(" \t", start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view field = Trim(text.substr(start, end - start));
    if (!field.empty() || commas) fields.push_back(field);
    start = end + 1;
  }
  return fields;
}

// One inverse response from calibrate's per-channel columns: each code's geometric mean over
// the channels, kept strictly increasing.
std::vector<double> GeometricMeanCurve(const std::vector<std::vector<double>>& columns) {
  std::vector<double> x(columns.front().size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    double log_sum = 0;
    for (const auto& column : columns) log_sum += std::log(std::max(column[i], 1e-300));
    x[i] = i == 0 && columns.front()[0] == 0 ? 0.0 : std::exp(log_sum / columns.size());
    if (i > 0) x[i] = std::max(x[i], std::nextafter(x[i - 1], 1e308));
  }
  return x;
}

}  // namespace

std::unique_ptr<TableCrf> TableCrf::FromCsv(const std::string& path) {
  // A missing file, a device or a FIFO is refused before it is opened, saying what it was for.
  if (const std::string problem = InputFileProblem(path); !problem.empty())
    Fail("{}: cannot open CRF table: {}", path, problem);
  // calibrate's per-channel layout (code,r,g,b): one curve, each code's geometric mean.
  if (const auto columns = ReadPerChannelResponse(path))
    return FromCodes(GeometricMeanCurve(*columns), path);
  std::ifstream in(path);
  if (!in) Fail("{}: cannot open CRF table ({})", path, std::strerror(errno));
  std::vector<std::vector<double>> rows;
  std::vector<int> row_lines;
  std::string line;
  int line_number = 0;
  bool seen_content = false;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string_view text = Trim(line);
    if (text.empty() || text.front() == '#') continue;
    const std::vector<std::string_view> fields = SplitCsvFields(text);
    std::vector<double> values(fields.size());
    bool numeric = true;
    for (std::size_t i = 0; i < fields.size(); ++i) numeric &= ParseDouble(fields[i], values[i]);
    const bool first = !seen_content;
    seen_content = true;
    if (!numeric) {
      bool any_number = false;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        double ignored;
        any_number |= ParseDouble(fields[i], ignored);
      }
      if (first && !any_number) continue;  // a text header such as "x,y"
      Fail("{}:{}: '{}' is not a row of numbers", path, line_number, std::string(text));
    }
    if (fields.size() != 1 && fields.size() != 2) {
      Fail("{}:{}: {} columns; a CRF table has one column (x per code) or two (x,y)", path,
           line_number, fields.size());
    }
    if (!rows.empty() && fields.size() != rows.front().size()) {
      Fail("{}:{}: {} columns, but line {} has {}", path, line_number, fields.size(),
           row_lines.front(), rows.front().size());
    }
    rows.push_back(std::move(values));
    row_lines.push_back(line_number);
  }
  if (in.bad()) Fail("{}: read error", path);
  if (rows.empty()) Fail("{}: no data rows in the CRF table", path);

  const std::size_t n = rows.size();
  std::vector<double> x(n), y(n);
  if (rows.front().size() == 1) {
    if (n < 2) Fail("{}: one code value; a per-code inverse response needs at least 2", path);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = rows[i][0];
      y[i] = static_cast<double>(i) / static_cast<double>(n - 1);
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = rows[i][0];
      y[i] = rows[i][1];
    }
  }
  CheckNodes(x, y, [&](std::size_t i) { return fmt::format("{}:{}", path, row_lines[i]); });
  return std::make_unique<TableCrf>(std::move(x), std::move(y), path);
}

double TableCrf::Apply(double x) const {
  if (std::isnan(x)) return x;
  x = ClampExposure(x);
  if (x >= x_.back()) return y_.back();
  // The segment [x_i, x_{i+1}) holding x.
  const std::size_t i = std::upper_bound(x_.begin(), x_.end(), x) - x_.begin() - 1;
  const double t = (x - x_[i]) / (x_[i + 1] - x_[i]);
  return y_[i] + t * (y_[i + 1] - y_[i]);
}

double TableCrf::Inverse(double y) const {
  if (!invertible_) {
    Fail(
        "CRF table {}: not invertible (a flat piece strictly between y = 0 and y = 1 maps "
        "many exposures to one display value)",
        source_);
  }
  if (std::isnan(y)) return y;
  if (y <= 0.0) return 0.0;
  if (y >= 1.0) return x_sat_;
  // The first node with y_j >= y; y_0 = 0 < y, so j >= 1 and y_{j-1} < y <= y_j.
  const std::size_t j = std::lower_bound(y_.begin(), y_.end(), y) - y_.begin();
  const double t = (y - y_[j - 1]) / (y_[j] - y_[j - 1]);
  return x_[j - 1] + t * (x_[j] - x_[j - 1]);
}

double TableCrf::Derivative(double x) const {
  if (std::isnan(x)) return x;
  x = ClampExposure(x);
  if (x > x_.back()) return 0.0;
  // The segment (x_{i-1}, x_i] holding x (the left one at a node), the first one at x = 0.
  std::size_t i = std::lower_bound(x_.begin(), x_.end(), x) - x_.begin();
  i = std::max<std::size_t>(i, 1);
  return (y_[i] - y_[i - 1]) / (x_[i] - x_[i - 1]);
}

nlohmann::json TableCrf::ToJson() const {
  return {{"model", "table"}, {"path", source_}, {"x", x_}, {"y", y_}};
}

// ---------------------------------------------------------------------------------------------
// Parsing

namespace {

constexpr const char* kSpecHelp =
    "expected linear, gamma[:<gamma>], srgb, filmic[:<contrast>,<mid>], "
    "naka-rushton:<k>,<gamma> or table:<file.csv>";

double SpecNumber(const std::string& spec, std::string_view text, const char* what) {
  double value;
  if (!ParseDouble(text, value)) {
    Fail("CRF spec '{}': {} '{}' is not a number", spec, what, std::string(text));
  }
  return value;
}

}  // namespace

std::unique_ptr<Crf> ParseCrf(const std::string& spec) {
  const std::size_t colon = spec.find(':');
  const std::string model = spec.substr(0, colon);
  const bool has_args = colon != std::string::npos;
  const std::string args = has_args ? spec.substr(colon + 1) : std::string();
  try {
    if (model == "linear" || model == "srgb") {
      if (has_args) Fail("CRF spec '{}': '{}' takes no parameters", spec, model);
      if (model == "linear") return std::make_unique<LinearCrf>();
      return std::make_unique<SrgbCrf>();
    }
    if (model == "gamma") {
      if (!has_args) return std::make_unique<GammaCrf>();
      return std::make_unique<GammaCrf>(SpecNumber(spec, args, "gamma"));
    }
    if (model == "filmic") {
      if (!has_args) return std::make_unique<FilmicCrf>();
      const std::size_t comma = args.find(',');
      if (comma == std::string::npos) {
        Fail(
            "CRF spec '{}': filmic takes two parameters, filmic:<contrast>,<mid> (e.g. "
            "filmic:{},{})",
            spec, FilmicCrf::kDefaultContrast, FilmicCrf::kDefaultMid);
      }
      const std::string_view view(args);
      return std::make_unique<FilmicCrf>(SpecNumber(spec, view.substr(0, comma), "contrast"),
                                         SpecNumber(spec, view.substr(comma + 1), "mid"));
    }
    if (model == "naka-rushton") {
      const std::size_t comma = args.find(',');
      if (!has_args || comma == std::string::npos) {
        Fail(
            "CRF spec '{}': naka-rushton takes two parameters, naka-rushton:<k>,<gamma> (e.g. "
            "naka-rushton:0.2,2.2)",
            spec);
      }
      const std::string_view view(args);
      return std::make_unique<NakaRushtonCrf>(SpecNumber(spec, view.substr(0, comma), "k"),
                                              SpecNumber(spec, view.substr(comma + 1), "gamma"));
    }
    if (model == "table") {
      if (args.empty()) Fail("CRF spec '{}': table needs a file, table:<file.csv>", spec);
      return TableCrf::FromCsv(args);
    }
  } catch (const Error& e) {
    if (std::string_view(e.what()).starts_with("CRF spec")) throw;
    Fail("CRF spec '{}': {}", spec, e.what());
  }
  Fail("CRF spec '{}': unknown model '{}'; {}", spec, model, kSpecHelp);
}

namespace {

double JsonNumber(const nlohmann::json& json, const char* key, double fallback) {
  if (!json.contains(key)) return fallback;
  const nlohmann::json& value = json.at(key);
  if (!value.is_number()) Fail("CRF JSON: \"{}\" must be a number, got {}", key, JsonPreview(value));
  return value.get<double>();
}

std::vector<double> JsonNumbers(const nlohmann::json& json, const char* key) {
  const nlohmann::json& value = json.at(key);
  if (!value.is_array()) Fail("CRF JSON: \"{}\" must be an array of numbers", key);
  std::vector<double> out;
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (!value[i].is_number()) {
      Fail("CRF JSON: \"{}\"[{}] must be a number, got {}", key, i, JsonPreview(value[i]));
    }
    out.push_back(value[i].get<double>());
  }
  return out;
}

}  // namespace

std::unique_ptr<Crf> CrfFromJson(const nlohmann::json& json) {
  if (!json.is_object()) Fail("CRF JSON: expected an object, got {}", JsonPreview(json));
  if (!json.contains("model") || !json.at("model").is_string()) {
    Fail("CRF JSON: missing string \"model\" ({}) in {}", kSpecHelp, JsonPreview(json));
  }
  const std::string model = json.at("model").get<std::string>();
  try {
    if (model == "linear") return std::make_unique<LinearCrf>();
    if (model == "srgb") return std::make_unique<SrgbCrf>();
    if (model == "gamma") {
      return std::make_unique<GammaCrf>(JsonNumber(json, "gamma", GammaCrf::kDefaultGamma));
    }
    if (model == "filmic") {
      return std::make_unique<FilmicCrf>(JsonNumber(json, "contrast", FilmicCrf::kDefaultContrast),
                                         JsonNumber(json, "mid", FilmicCrf::kDefaultMid));
    }
    if (model == "naka-rushton") {
      if (!json.contains("half") || !json.contains("gamma"))
        Fail("CRF JSON: naka-rushton needs \"half\" and \"gamma\" in {}", json.dump());
      return std::make_unique<NakaRushtonCrf>(JsonNumber(json, "half", 0.0),
                                              JsonNumber(json, "gamma", 0.0));
    }
    if (model == "table") {
      std::string path;
      if (json.contains("path")) {
        if (!json.at("path").is_string()) Fail("CRF JSON: \"path\" must be a string");
        path = json.at("path").get<std::string>();
      }
      if (json.contains("x") || json.contains("y")) {
        if (!json.contains("x") || !json.contains("y")) {
          Fail("CRF JSON: a table needs both \"x\" and \"y\"");
        }
        return std::make_unique<TableCrf>(JsonNumbers(json, "x"), JsonNumbers(json, "y"),
                                          path.empty() ? "(inline)" : path);
      }
      if (path.empty()) Fail("CRF JSON: a table needs \"x\" and \"y\" nodes or a \"path\"");
      return TableCrf::FromCsv(path);
    }
  } catch (const Error& e) {
    if (std::string_view(e.what()).starts_with("CRF JSON")) throw;
    Fail("CRF JSON: {}", e.what());
  }
  Fail("CRF JSON: unknown model '{}'; {}", model, kSpecHelp);
}

}  // namespace hdr4d
