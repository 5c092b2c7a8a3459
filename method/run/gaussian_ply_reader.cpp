#include "method/run/gaussian_ply_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/util/error.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

struct PlyTable {
  std::vector<std::string> columns;
  std::map<std::string, std::vector<double>> comments;
  std::map<std::string, std::string> comment_text;
  std::size_t vertices = 0;
  std::vector<float> values;  // vertices x columns
  int Column(const std::string& name) const {
    for (std::size_t k = 0; k < columns.size(); ++k)
      if (columns[k] == name) return static_cast<int>(k);
    return -1;
  }
};

void ReadComment(std::istringstream& words, PlyTable* table) {
  std::string key;
  words >> key;
  if (key.rfind("hdr4d-", 0) != 0) return;
  if (!key.empty() && key.back() == ':') key.pop_back();
  std::vector<double>& numbers = table->comments[key];
  std::string rest;
  std::getline(words, rest);
  table->comment_text[key] = rest.empty() ? rest : rest.substr(1);
  words = std::istringstream(rest);
  std::string word;
  while (words >> word) {
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') break;
    numbers.push_back(v);
  }
}

PlyTable ReadTable(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail("{}: cannot open", path.string());
  PlyTable table;
  std::string line;
  if (!std::getline(in, line) || line != "ply") Fail("{}: not a .ply file", path.string());
  bool format_ok = false;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream words(line);
    std::string word, type, name;
    words >> word;
    if (word == "format") {
      words >> type;
      format_ok = type == "binary_little_endian";
    } else if (word == "comment") {
      ReadComment(words, &table);
    } else if (word == "element") {
      words >> name >> table.vertices;
      if (name != "vertex" || !table.columns.empty())
        Fail("{}: expected one element 'vertex', found '{}'", path.string(), line);
    } else if (word == "property") {
      words >> type >> name;
      if (type != "float" && type != "float32")
        Fail("{}: property '{}' is {}; hdr4d reads float columns only", path.string(), name, type);
      table.columns.push_back(name);
    }
  }
  if (line != "end_header") Fail("{}: the header has no end_header", path.string());
  if (!format_ok) Fail("{}: not binary_little_endian", path.string());
  table.values.resize(table.vertices * table.columns.size());
  in.read(reinterpret_cast<char*>(table.values.data()),
          static_cast<std::streamsize>(table.values.size() * sizeof(float)));
  if (static_cast<std::size_t>(in.gcount()) != table.values.size() * sizeof(float))
    Fail("{}: the body holds fewer than {} vertices of {} floats", path.string(), table.vertices,
         table.columns.size());
  return table;
}

// Copies `count` columns named prefix0..prefix{count-1} of every vertex into out[i * stride + k].
void CopyColumns(const PlyTable& table, const fs::path& path, const std::string& prefix, int count,
                 std::vector<float>* out, std::size_t stride, std::size_t offset = 0) {
  for (int k = 0; k < count; ++k) {
    const int col = table.Column(prefix + std::to_string(k));
    if (col < 0) Fail("{}: no column '{}{}'", path.string(), prefix, k);
    for (std::size_t i = 0; i < table.vertices; ++i)
      (*out)[i * stride + offset + k] = table.values[i * table.columns.size() + col];
  }
}

// SH degree D with 3 ((D+1)^2 - 1) f_rest columns (0..3), from the count of `prefix` columns.
int ShDegreeOf(const PlyTable& table, const fs::path& path, const std::string& prefix) {
  int rest = 0;
  while (table.Column(prefix + std::to_string(rest)) >= 0) ++rest;
  for (int d = 0; d <= 3; ++d)
    if (rest == 3 * ((d + 1) * (d + 1) - 1)) return d;
  Fail("{}: {} {}* columns is no SH degree (0, 9, 24 or 45 expected)", path.string(), rest, prefix);
}

// Channel-major rest columns (c * (K - 1) + k) into the model's coefficient-major layout.
void CopyRest(const PlyTable& table, const fs::path& path, const std::string& prefix,
              GaussianModel* m) {
  const int rest = m->basis.coefficients() - 1, channels = m->channels;
  std::vector<float> cm(table.vertices * rest * channels);
  CopyColumns(table, path, prefix, rest * channels, &cm, rest * channels);
  for (std::size_t i = 0; i < table.vertices; ++i)
    for (int c = 0; c < channels; ++c)
      for (int k = 0; k < rest; ++k)
        m->color_rest[i * m->rest_stride() + k * channels + c] = cm[i * rest * channels + c * rest + k];
}

void ReadSlice(const PlyTable& table, const fs::path& path, GaussianPly* out) {
  GaussianModel& m = out->model;
  const bool hdr = table.Column("f_hdr_dc_0") >= 0;
  m.temporal = false;
  m.color_mode = hdr ? ColorMode::kLogHdr : ColorMode::kLdr;
  m.basis = {ShDegreeOf(table, path, hdr ? "f_hdr_rest_" : "f_rest_"), 0};
  m.Resize(table.vertices);
  for (int a = 0; a < 3; ++a) {
    const char* name = a == 0 ? "x" : a == 1 ? "y" : "z";
    const int col = table.Column(name);
    if (col < 0) Fail("{}: no column '{}'", path.string(), name);
    for (std::size_t i = 0; i < table.vertices; ++i)
      m.xyz[i * 3 + a] = table.values[i * table.columns.size() + col];
  }
  CopyColumns(table, path, "scale_", 3, &m.log_scales, 4);
  CopyColumns(table, path, "rot_", 4, &m.rot_left, 4);
  const int op = table.Column("opacity");
  if (op < 0) Fail("{}: no column 'opacity'", path.string());
  for (std::size_t i = 0; i < table.vertices; ++i)
    m.opacity_logit[i] = table.values[i * table.columns.size() + op];
  CopyColumns(table, path, hdr ? "f_hdr_dc_" : "f_dc_", 3, &m.color_dc, 3);
  CopyRest(table, path, hdr ? "f_hdr_rest_" : "f_rest_", &m);
}

void Read4d(const PlyTable& table, const fs::path& path, GaussianPly* out) {
  GaussianModel& m = out->model;
  auto comment = [&](const char* key, std::size_t n) -> const std::vector<double>& {
    auto it = table.comments.find(key);
    if (it == table.comments.end() || it->second.size() < n)
      Fail("{}: the header lacks 'comment {}' with {} number(s)", path.string(), key, n);
    return it->second;
  };
  m.temporal = comment("hdr4d-temporal", 1)[0] != 0;
  const auto& basis = comment("hdr4d-basis", 2);
  m.basis = {static_cast<int>(basis[0]), static_cast<int>(basis[1])};
  m.color_mode = table.comment_text.count("hdr4d-colour") &&
                         table.comment_text.at("hdr4d-colour").rfind("log-hdr", 0) == 0 ? ColorMode::kLogHdr : ColorMode::kLdr;
  int channels = 0;
  while (table.Column("f_dc_" + std::to_string(channels)) >= 0) ++channels;
  m.channels = std::max(channels, 1);
  if (m.basis.max_sh_degree < 0 || m.basis.max_sh_degree > 3 || m.basis.max_time_degree < 0 ||
      m.basis.max_time_degree > 2)
    Fail("{}: colour basis {} {} out of range", path.string(), basis[0], basis[1]);
  m.Resize(table.vertices);
  const char* xyz[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const int col = table.Column(xyz[a]);
    if (col < 0) Fail("{}: no column '{}'", path.string(), xyz[a]);
    for (std::size_t i = 0; i < table.vertices; ++i)
      m.xyz[i * 3 + a] = table.values[i * table.columns.size() + col];
  }
  for (auto [name, buffer] : {std::pair{"t", &m.t}, std::pair{"opacity", &m.opacity_logit}}) {
    const int col = table.Column(name);
    if (col < 0) Fail("{}: no column '{}'", path.string(), name);
    for (std::size_t i = 0; i < table.vertices; ++i)
      (*buffer)[i] = table.values[i * table.columns.size() + col];
  }
  CopyColumns(table, path, "scale_", 4, &m.log_scales, 4);
  CopyColumns(table, path, "rot_", 4, &m.rot_left, 4);
  CopyColumns(table, path, "rotr_", 4, &m.rot_right, 4);
  CopyColumns(table, path, "f_dc_", m.channels, &m.color_dc, m.channels);
  CopyRest(table, path, "f_rest_", &m);
  if (table.Column("hdr_offset_0") >= 0) {
    out->hdr_offset.resize(table.vertices * 3);
    CopyColumns(table, path, "hdr_offset_", 3, &out->hdr_offset, 3);
  }
}

}  // namespace

GaussianPly ReadGaussianPly(const fs::path& path) {
  const PlyTable table = ReadTable(path);
  GaussianPly out;
  out.comments = table.comments;
  out.comment_text = table.comment_text;
  out.four_d = table.comments.count("hdr4d-4d-ply") > 0;
  if (out.four_d)
    Read4d(table, path, &out);
  else
    ReadSlice(table, path, &out);
  return out;
}

}  // namespace hdr4d::method
