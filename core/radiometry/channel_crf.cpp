#include "core/radiometry/channel_crf.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/util/error.h"

namespace hdr4d {
namespace {

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) {
    const auto first = field.find_first_not_of(" \t\r");
    const auto last = field.find_last_not_of(" \t\r");
    fields.push_back(first == std::string::npos ? std::string() : field.substr(first, last - first + 1));
  }
  return fields;
}

bool ToDouble(const std::string& text, double* out) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *out);
  return !text.empty() && ec == std::errc() && ptr == end && std::isfinite(*out);
}

// The first line that is neither blank nor a comment, or "" at the end.
bool NextContent(std::ifstream& in, std::string* line, int* number) {
  while (std::getline(in, *line)) {
    ++*number;
    const auto first = line->find_first_not_of(" \t\r");
    if (first != std::string::npos && (*line)[first] != '#') return true;
  }
  return false;
}

void AddRow(const std::string& path, int number, const std::vector<std::string>& fields,
            std::vector<std::vector<double>>* columns) {
  if (fields.size() != columns->size() + 1)
    Fail("{}:{}: {} fields; the header names {}", path, number, fields.size(), columns->size() + 1);
  double code = 0;
  const std::size_t expected = columns->front().size();
  if (!ToDouble(fields[0], &code) || code != static_cast<double>(expected))
    Fail("{}:{}: code '{}' where {} was expected (codes count up from 0)", path, number, fields[0], expected);
  for (std::size_t c = 0; c < columns->size(); ++c) {
    double x = 0;
    if (!ToDouble(fields[c + 1], &x) || x < 0)
      Fail("{}:{}: '{}' is not an exposure (a finite number >= 0)", path, number, fields[c + 1]);
    auto& column = (*columns)[c];
    if (!column.empty() && x < column.back())
      Fail("{}:{}: x = {} is below the previous code's {}; a response must not decrease", path, number,
           x, column.back());
    if (!column.empty() && x == column.back()) x = std::nextafter(std::max(x, 1e-300), 1e308);
    column.push_back(x);
  }
}

}  // namespace

std::optional<std::vector<std::vector<double>>> ReadPerChannelResponse(const std::string& path) {
  std::ifstream in(path);
  if (!in) Fail("{}: cannot open CRF table ({})", path, std::strerror(errno));
  std::string line;
  int number = 0;
  if (!NextContent(in, &line, &number)) return std::nullopt;
  const std::vector<std::string> header = SplitFields(line);
  std::string first = header.empty() ? "" : header[0];
  std::transform(first.begin(), first.end(), first.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (first != "code") return std::nullopt;
  if (header.size() < 2) Fail("{}:{}: a 'code' column but no channel after it", path, number);
  std::vector<std::vector<double>> columns(header.size() - 1);
  while (NextContent(in, &line, &number)) AddRow(path, number, SplitFields(line), &columns);
  if (in.bad()) Fail("{}: read error", path);
  if (columns.front().size() < 2)
    Fail("{}: {} code rows; a response table needs at least 2", path, columns.front().size());
  return columns;
}

std::vector<std::unique_ptr<Crf>> ParseChannelCrfs(const std::string& spec) {
  std::vector<std::unique_ptr<Crf>> curves;
  if (spec.rfind("table:", 0) == 0) {
    const std::string path = spec.substr(6);
    if (const auto columns = ReadPerChannelResponse(path); columns && columns->size() > 1) {
      for (const auto& x : *columns) curves.push_back(TableCrf::FromCodes(x, path));
      return curves;
    }
  }
  curves.push_back(ParseCrf(spec));
  return curves;
}

}  // namespace hdr4d
