#include "core/geometry/ply.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>

#include "core/files/file_access.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little,
              "the PLY reader copies little-endian values as they are");

namespace {

enum class Scalar { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

struct ScalarType {
  std::string_view name;
  Scalar scalar;
};

constexpr ScalarType kScalarTypes[] = {
    {"char", Scalar::kInt8},       {"int8", Scalar::kInt8},       {"uchar", Scalar::kUint8},
    {"uint8", Scalar::kUint8},     {"short", Scalar::kInt16},     {"int16", Scalar::kInt16},
    {"ushort", Scalar::kUint16},   {"uint16", Scalar::kUint16},   {"int", Scalar::kInt32},
    {"int32", Scalar::kInt32},     {"uint", Scalar::kUint32},     {"uint32", Scalar::kUint32},
    {"float", Scalar::kFloat32},   {"float32", Scalar::kFloat32}, {"double", Scalar::kFloat64},
    {"float64", Scalar::kFloat64},
};

int ByteSize(Scalar s) {
  switch (s) {
    case Scalar::kInt8:
    case Scalar::kUint8:
      return 1;
    case Scalar::kInt16:
    case Scalar::kUint16:
      return 2;
    case Scalar::kInt32:
    case Scalar::kUint32:
    case Scalar::kFloat32:
      return 4;
    case Scalar::kFloat64:
      return 8;
  }
  return 0;
}

bool IsFloat(Scalar s) { return s == Scalar::kFloat32 || s == Scalar::kFloat64; }

// The largest value of an integer type: colours stored as integers are scaled by it.
double IntegerMax(Scalar s) {
  switch (s) {
    case Scalar::kInt8:
      return 127;
    case Scalar::kUint8:
      return 255;
    case Scalar::kInt16:
      return 32767;
    case Scalar::kUint16:
      return 65535;
    case Scalar::kInt32:
      return 2147483647.0;
    case Scalar::kUint32:
      return 4294967295.0;
    default:
      return 1;
  }
}

template <typename T>
double Load(const char* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return static_cast<double>(value);
}

double LoadScalar(const char* p, Scalar s) {
  switch (s) {
    case Scalar::kInt8:
      return Load<std::int8_t>(p);
    case Scalar::kUint8:
      return Load<std::uint8_t>(p);
    case Scalar::kInt16:
      return Load<std::int16_t>(p);
    case Scalar::kUint16:
      return Load<std::uint16_t>(p);
    case Scalar::kInt32:
      return Load<std::int32_t>(p);
    case Scalar::kUint32:
      return Load<std::uint32_t>(p);
    case Scalar::kFloat32:
      return Load<float>(p);
    case Scalar::kFloat64:
      return Load<double>(p);
  }
  return 0;
}

struct Property {
  std::string name;
  Scalar type = Scalar::kFloat32;
  bool is_list = false;
  Scalar count_type = Scalar::kUint8;  // lists only
};

struct Element {
  std::string name;
  std::int64_t count = 0;
  std::vector<Property> properties;
};

enum class Format { kAscii, kBinaryLittleEndian };

struct Header {
  Format format = Format::kAscii;
  std::vector<Element> elements;
  std::size_t data_offset = 0;
};

std::vector<std::string> SplitWords(std::string_view line) {
  std::vector<std::string> words;
  std::istringstream in{std::string(line)};
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

Header ParseHeader(const fs::path& path, const std::string& bytes) {
  const std::string name = path.string();
  if (bytes.rfind("ply", 0) != 0 || bytes.size() < 4 || (bytes[3] != '\n' && bytes[3] != '\r')) {
    Fail("{}: bad PLY header: the file does not start with 'ply'", name);
  }
  auto scalar_type = [&](const std::string& word, int line_no) {
    for (const ScalarType& t : kScalarTypes) {
      if (t.name == word) return t.scalar;
    }
    Fail("{}: bad PLY header: line {}: unknown property type '{}'", name, line_no, word);
  };
  Header header;
  bool have_format = false, ended = false;
  std::size_t pos = 0;
  int line_no = 0;
  while (pos < bytes.size()) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string_view line(bytes.data() + pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = eol + 1;
    ++line_no;
    const std::vector<std::string> w = SplitWords(line);
    if (line_no == 1 || w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
      break;
    }
    if (w[0] == "format") {
      if (w.size() != 3) Fail("{}: bad PLY header: line {}: malformed format line", name, line_no);
      if (w[1] == "ascii") {
        header.format = Format::kAscii;
      } else if (w[1] == "binary_little_endian") {
        header.format = Format::kBinaryLittleEndian;
      } else if (w[1] == "binary_big_endian") {
        Fail("{}: unsupported PLY format binary_big_endian (use ascii or binary_little_endian)",
             name);
      } else {
        Fail("{}: bad PLY header: line {}: unknown format '{}'", name, line_no, w[1]);
      }
      have_format = true;
    } else if (w[0] == "element") {
      std::int64_t count = -1;
      if (w.size() == 3) {
        const auto [p, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), count);
        if (ec != std::errc() || p != w[2].data() + w[2].size()) count = -1;
      }
      if (count < 0) Fail("{}: bad PLY header: line {}: malformed element line", name, line_no);
      header.elements.push_back({w[1], count, {}});
    } else if (w[0] == "property") {
      if (header.elements.empty()) {
        Fail("{}: bad PLY header: line {}: property before any element", name, line_no);
      }
      Property prop;
      if (w.size() == 5 && w[1] == "list") {
        prop = {w[4], scalar_type(w[3], line_no), true, scalar_type(w[2], line_no)};
        if (IsFloat(prop.count_type)) {
          Fail("{}: bad PLY header: line {}: list count type must be an integer", name, line_no);
        }
      } else if (w.size() == 3) {
        prop = {w[2], scalar_type(w[1], line_no), false, Scalar::kUint8};
      } else {
        Fail("{}: bad PLY header: line {}: malformed property line", name, line_no);
      }
      header.elements.back().properties.push_back(prop);
    } else {
      Fail("{}: bad PLY header: line {}: unknown keyword '{}'", name, line_no, w[0]);
    }
  }
  if (!ended) Fail("{}: bad PLY header: no end_header line", name);
  if (!have_format) Fail("{}: bad PLY header: no format line", name);
  header.data_offset = pos;
  return header;
}

// Reads values in file order, either from ascii tokens or from little-endian bytes.
class ValueReader {
 public:
  ValueReader(const fs::path& path, const std::string& bytes, std::size_t offset, Format format)
      : path_(path), bytes_(bytes), pos_(offset), format_(format) {}

  // False when the data ran out (the caller reports what it was reading).
  bool Next(Scalar type, double* value) {
    if (format_ == Format::kBinaryLittleEndian) {
      const int size = ByteSize(type);
      if (bytes_.size() - pos_ < static_cast<std::size_t>(size)) return false;
      *value = LoadScalar(bytes_.data() + pos_, type);
      pos_ += size;
      return true;
    }
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    if (pos_ >= bytes_.size()) return false;
    std::size_t end = pos_;
    while (end < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[end]))) ++end;
    const char* first = bytes_.data() + pos_;
    const char* last = bytes_.data() + end;
    const auto [p, ec] = std::from_chars(first, last, *value);
    if (ec != std::errc() || p != last) {
      Fail("{}: bad number '{}' in PLY data", path_.string(), std::string(first, last));
    }
    pos_ = end;
    return true;
  }

  std::size_t remaining() const { return bytes_.size() - pos_; }
  void Skip(std::size_t n) { pos_ += n; }
  Format format() const { return format_; }

 private:
  const fs::path& path_;
  const std::string& bytes_;
  std::size_t pos_;
  Format format_;
};

// Skips one element's data, item by item when it has list properties.
void SkipElement(const fs::path& path, const Element& element, ValueReader& reader) {
  const auto truncated = [&](std::int64_t item) {
    Fail("{}: truncated PLY data in element '{}' (item {} of {})", path.string(), element.name,
         item, element.count);
  };
  const bool has_list = std::any_of(element.properties.begin(), element.properties.end(),
                                    [](const Property& p) { return p.is_list; });
  if (reader.format() == Format::kBinaryLittleEndian && !has_list) {
    std::size_t stride = 0;
    for (const Property& p : element.properties) stride += ByteSize(p.type);
    if (stride > 0 && static_cast<std::uint64_t>(element.count) > reader.remaining() / stride) {
      truncated(static_cast<std::int64_t>(reader.remaining() / stride));
    }
    reader.Skip(stride * element.count);
    return;
  }
  double value = 0;
  for (std::int64_t i = 0; i < element.count; ++i) {
    for (const Property& p : element.properties) {
      if (!p.is_list) {
        if (!reader.Next(p.type, &value)) truncated(i);
        continue;
      }
      if (!reader.Next(p.count_type, &value)) truncated(i);
      if (value < 0) Fail("{}: negative list length in element '{}'", path.string(), element.name);
      const auto n = static_cast<std::int64_t>(value);
      for (std::int64_t k = 0; k < n; ++k) {
        if (!reader.Next(p.type, &value)) truncated(i);
      }
    }
  }
}

std::string ReadAllBytes(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) Fail("{}: file not found", path.string());
  if (fs::is_directory(path, ec)) Fail("{}: is a folder, expected a PLY file", path.string());
  RequireInputFile(path);  // a device or FIFO is refused before it is opened
  std::ifstream file(path, std::ios::binary);
  if (!file) Fail("{}: cannot open for reading", path.string());
  std::ostringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

// The vertex element's columns this reader uses (-1 when absent): x, y, z are required, the
// colour all three or none, time optional. List properties are refused.
struct VertexColumns {
  int x, y, z, red, green, blue, time;
  bool has_colors, has_time;
};

VertexColumns FindVertexColumns(const Element& vertex, const std::string& name) {
  auto find = [&](std::string_view prop) {
    for (std::size_t i = 0; i < vertex.properties.size(); ++i) {
      if (vertex.properties[i].name == prop) return static_cast<int>(i);
    }
    return -1;
  };
  for (const Property& p : vertex.properties) {
    if (p.is_list) Fail("{}: unsupported list property '{}' in the vertex element", name, p.name);
  }
  VertexColumns c;
  c.x = find("x"), c.y = find("y"), c.z = find("z");
  if (c.x < 0 || c.y < 0 || c.z < 0)
    Fail("{}: bad PLY header: the vertex element lacks x, y or z", name);
  c.red = find("red"), c.green = find("green"), c.blue = find("blue"), c.time = find("time");
  const int num_colors = (c.red >= 0) + (c.green >= 0) + (c.blue >= 0);
  if (num_colors != 0 && num_colors != 3) {
    Fail("{}: bad PLY header: the vertex element has only some of red, green, blue", name);
  }
  c.has_colors = num_colors == 3;
  c.has_time = c.time >= 0;
  return c;
}

// Vertex i from its row of values: the position, colour (integers scaled to [0, 1]) and time,
// each finite.
void AppendVertex(const std::vector<double>& row,
                  std::int64_t i,
                  const Element& vertex,
                  const VertexColumns& col,
                  const std::string& name,
                  PointCloud* cloud) {
  const Eigen::Vector3f p(row[col.x], row[col.y], row[col.z]);
  if (!p.allFinite()) {
    Fail("{}: vertex {} has a non-finite coordinate ({}, {}, {})", name, i, row[col.x], row[col.y],
         row[col.z]);
  }
  cloud->positions.push_back(p);
  if (col.has_colors) {
    Eigen::Vector3f c;
    const int cols[3] = {col.red, col.green, col.blue};
    for (int ch = 0; ch < 3; ++ch) {
      const Scalar type = vertex.properties[cols[ch]].type;
      c[ch] = static_cast<float>(IsFloat(type) ? row[cols[ch]] : row[cols[ch]] / IntegerMax(type));
    }
    if (!c.allFinite()) Fail("{}: vertex {} has a non-finite colour", name, i);
    cloud->colors.push_back(c);
  }
  if (col.has_time) {
    const auto t = static_cast<float>(row[col.time]);
    if (!std::isfinite(t)) Fail("{}: vertex {} has a non-finite time", name, i);
    cloud->times.push_back(t);
  }
}

}  // namespace

std::int64_t ReadPlyVertexCount(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) Fail("{}: file not found", path.string());
  RequireInputFile(path);  // a device or FIFO is refused before it is opened
  std::ifstream file(path, std::ios::binary);
  if (!file) Fail("{}: cannot open for reading", path.string());
  // The header only: a header longer than this is not one hdr4d reads either.
  std::string head(64 * 1024, '\0');
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(file.gcount()));
  const Header header = ParseHeader(path, head);
  for (const Element& e : header.elements)
    if (e.name == "vertex") return e.count;
  Fail("{}: bad PLY header: no vertex element", path.string());
}

PointCloud ReadPly(const fs::path& path) {
  const std::string bytes = ReadAllBytes(path);
  const std::string name = path.string();
  const Header header = ParseHeader(path, bytes);

  const auto vertex_it = std::find_if(header.elements.begin(), header.elements.end(),
                                      [](const Element& e) { return e.name == "vertex"; });
  if (vertex_it == header.elements.end()) Fail("{}: bad PLY header: no vertex element", name);
  const Element& vertex = *vertex_it;
  const VertexColumns columns = FindVertexColumns(vertex, name);

  ValueReader reader(path, bytes, header.data_offset, header.format);
  for (auto e = header.elements.begin(); e != vertex_it; ++e) SkipElement(path, *e, reader);

  const std::size_t num_props = vertex.properties.size();
  if (header.format == Format::kBinaryLittleEndian) {
    std::size_t stride = 0;
    for (const Property& p : vertex.properties) stride += ByteSize(p.type);
    const std::size_t available = stride > 0 ? reader.remaining() / stride : 0;
    if (static_cast<std::uint64_t>(vertex.count) > available) {
      Fail("{}: truncated PLY data: the header declares {} vertices, the file holds {}", name,
           vertex.count, available);
    }
  }

  PointCloud cloud;
  // An ascii header can claim any count; grow as data arrives instead of trusting it.
  const auto reserve = static_cast<std::size_t>(header.format == Format::kAscii
                                                    ? std::min<std::int64_t>(vertex.count, 1 << 20)
                                                    : vertex.count);
  cloud.positions.reserve(reserve);
  if (columns.has_colors) cloud.colors.reserve(reserve);
  if (columns.has_time) cloud.times.reserve(reserve);
  std::vector<double> row(num_props);
  for (std::int64_t i = 0; i < vertex.count; ++i) {
    for (std::size_t k = 0; k < num_props; ++k) {
      if (!reader.Next(vertex.properties[k].type, &row[k])) {
        Fail("{}: truncated PLY data: the header declares {} vertices, the file holds {}", name,
             vertex.count, i);
      }
    }
    AppendVertex(row, i, vertex, columns, name, &cloud);
  }
  return cloud;
}

void WritePly(const fs::path& path, const PointCloud& cloud, const PlyWriteOptions& options) {
  const std::size_t n = cloud.positions.size();
  if (!cloud.colors.empty() && cloud.colors.size() != n) {
    Fail("{}: point cloud has {} colours for {} points", path.string(), cloud.colors.size(), n);
  }
  if (!cloud.times.empty() && cloud.times.size() != n) {
    Fail("{}: point cloud has {} times for {} points", path.string(), cloud.times.size(), n);
  }
  const bool binary = options.format == PlyFormat::kBinaryLittleEndian;
  std::string out = "ply\n";
  out += binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
  out += "comment written by hdr4d\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (cloud.has_colors()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (cloud.has_times()) out += "property float time\n";
  out += "end_header\n";

  auto quantise = [](float c) {
    const float clamped = std::isnan(c) ? 0.0f : std::clamp(c, 0.0f, 1.0f);
    return static_cast<std::uint8_t>(std::lround(clamped * 255.0f));
  };
  auto append = [&out](const auto& value) {
    const char* p = reinterpret_cast<const char*>(&value);
    out.append(p, sizeof(value));
  };
  if (binary) {
    const std::size_t stride = 12 + (cloud.has_colors() ? 3 : 0) + (cloud.has_times() ? 4 : 0);
    out.reserve(out.size() + stride * n);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.positions[i];
    if (binary) {
      append(p.x()), append(p.y()), append(p.z());
      if (cloud.has_colors()) {
        for (int c = 0; c < 3; ++c) append(quantise(cloud.colors[i][c]));
      }
      if (cloud.has_times()) append(cloud.times[i]);
    } else {
      // {} prints the shortest representation that reads back to the same float.
      out += fmt::format("{} {} {}", p.x(), p.y(), p.z());
      if (cloud.has_colors()) {
        out += fmt::format(" {} {} {}", quantise(cloud.colors[i][0]), quantise(cloud.colors[i][1]),
                           quantise(cloud.colors[i][2]));
      }
      if (cloud.has_times()) out += fmt::format(" {}", cloud.times[i]);
      out += '\n';
    }
  }
  WriteTextFileAtomic(path, out);
}

}  // namespace hdr4d
