#include "method/tonemap/tone_mapper.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <limits>
#include <string_view>

#include "core/util/error.h"

namespace hdr4d::method {
namespace {

constexpr std::array<std::string_view, 5> kKinds = {"dtm", "mlp", "sigmoid", "reinhard", "durand"};
constexpr std::array<std::string_view, 4> kContextLearners = {"gru", "rnn", "lstm", "transformer"};

// Upper limits that keep a typo (an extra zero or three) from allocating gigabytes.
constexpr int kMaxTimes = 10'000'000;
constexpr int kMaxImages = 10'000'000;
constexpr int kMaxWindow = 4096;
constexpr int kMaxContextSize = 64;
constexpr int kMaxCurveHidden = 1024;
constexpr int kMaxTableNodes = 1 << 20;

template <std::size_t N>
bool OneOf(const std::string& value, const std::array<std::string_view, N>& names) {
  return std::find(names.begin(), names.end(), value) != names.end();
}

template <std::size_t N>
std::string Join(const std::array<std::string_view, N>& names) {
  std::string out;
  for (std::string_view n : names) out += (out.empty() ? "" : " | ") + std::string(n);
  return out;
}

std::string CheckRange(const char* key, long long value, long long lo, long long hi) {
  if (value < lo || value > hi) {
    return fmt::format("{} must be in [{}, {}] (got {})", key, lo, hi, value);
  }
  return "";
}

constexpr std::array<std::string_view, 13> kKeys = {
    "kind",         "num_times",    "num_images", "context_learner", "context_window",
    "context_size", "curve_hidden", "tabulated",  "table_nodes",     "seed",
    "monotone_curves", "monotone_form", "unseen_rows"};
constexpr std::array<std::string_view, 2> kUnseenRows = {"interpolate", "zero"};
// The construction of monotone curves (monotone_mlp.h). Configs with monotone curves and no
// form are from the earlier all-positive (convex) construction, which is gone.
constexpr std::string_view kMonotoneForm = "rising+falling";

const nlohmann::json& Member(const nlohmann::json& json,
                             const std::string& source,
                             std::string_view key) {
  const auto it = json.find(std::string(key));
  if (it == json.end()) Fail("{}: tone mapper config: missing key '{}'", source, key);
  return *it;
}

std::string ReadString(const nlohmann::json& json,
                       const std::string& source,
                       std::string_view key) {
  const nlohmann::json& v = Member(json, source, key);
  if (!v.is_string()) {
    Fail("{}: tone mapper config: '{}' must be a string (got {})", source, key, v.dump());
  }
  return v.get<std::string>();
}

int ReadInt(const nlohmann::json& json, const std::string& source, std::string_view key) {
  const nlohmann::json& v = Member(json, source, key);
  const bool fits = (v.is_number_unsigned() &&
                     v.get<std::uint64_t>() <= std::uint64_t(std::numeric_limits<int>::max())) ||
                    (v.is_number_integer() && !v.is_number_unsigned() &&
                     v.get<std::int64_t>() >= std::numeric_limits<int>::min() &&
                     v.get<std::int64_t>() <= std::numeric_limits<int>::max());
  if (!fits)
    Fail("{}: tone mapper config: '{}' must be an integer (got {})", source, key, v.dump());
  return static_cast<int>(v.get<std::int64_t>());
}

}  // namespace

std::string ToneMapperConfig::Validate() const {
  if (!OneOf(kind, kKinds)) {
    return fmt::format("kind must be one of {} (got '{}')", Join(kKinds), kind);
  }
  if (!OneOf(context_learner, kContextLearners)) {
    return fmt::format("context_learner must be one of {} (got '{}')", Join(kContextLearners),
                       context_learner);
  }
  if (!OneOf(unseen_rows, kUnseenRows)) {
    return fmt::format("unseen_rows must be one of {} (got '{}')", Join(kUnseenRows), unseen_rows);
  }
  for (const std::string& problem : {
           CheckRange("num_times", num_times, 1, kMaxTimes),
           CheckRange("num_images", num_images, 0, kMaxImages),
           CheckRange("context_window", context_window, 1, kMaxWindow),
           CheckRange("context_size", context_size, 1, kMaxContextSize),
           CheckRange("curve_hidden", curve_hidden, 1, kMaxCurveHidden),
           CheckRange("table_nodes", table_nodes, 2, kMaxTableNodes),
       }) {
    if (!problem.empty()) return problem;
  }
  return "";
}

nlohmann::json ToneMapperConfig::ToJson() const {
  nlohmann::json j = {{"kind", kind},
          {"num_times", num_times},
          {"num_images", num_images},
          {"context_learner", context_learner},
          {"context_window", context_window},
          {"context_size", context_size},
          {"curve_hidden", curve_hidden},
          {"tabulated", tabulated},
          {"table_nodes", table_nodes},
          {"seed", seed},
          {"monotone_curves", monotone_curves},
          {"unseen_rows", unseen_rows}};
  if (monotone_curves) j["monotone_form"] = kMonotoneForm;
  return j;
}

ToneMapperConfig ToneMapperConfig::FromJson(const nlohmann::json& json, const std::string& source) {
  if (!json.is_object()) {
    Fail("{}: tone mapper config must be a JSON object (got {})", source, json.type_name());
  }
  for (const auto& item : json.items()) {
    if (!OneOf(item.key(), kKeys)) {
      Fail("{}: tone mapper config: unknown key '{}' (known: {})", source, item.key(), Join(kKeys));
    }
  }
  ToneMapperConfig c;
  c.kind = ReadString(json, source, "kind");
  c.num_times = ReadInt(json, source, "num_times");
  c.num_images = ReadInt(json, source, "num_images");
  c.context_learner = ReadString(json, source, "context_learner");
  c.context_window = ReadInt(json, source, "context_window");
  c.context_size = ReadInt(json, source, "context_size");
  c.curve_hidden = ReadInt(json, source, "curve_hidden");
  const nlohmann::json& tabulated = Member(json, source, "tabulated");
  if (!tabulated.is_boolean()) {
    Fail("{}: tone mapper config: 'tabulated' must be true or false (got {})", source,
         tabulated.dump());
  }
  c.tabulated = tabulated.get<bool>();
  c.table_nodes = ReadInt(json, source, "table_nodes");
  const nlohmann::json& seed = Member(json, source, "seed");
  if (!seed.is_number_integer() || (!seed.is_number_unsigned() && seed.get<std::int64_t>() < 0)) {
    Fail("{}: tone mapper config: 'seed' must be a non-negative integer (got {})", source,
         seed.dump());
  }
  c.seed = seed.get<std::uint64_t>();
  // Runs from before the key existed had the reference's free curves.
  c.monotone_curves = false;
  if (const auto it = json.find("monotone_curves"); it != json.end()) {
    if (!it->is_boolean()) {
      Fail("{}: tone mapper config: 'monotone_curves' must be true or false (got {})", source,
           it->dump());
    }
    c.monotone_curves = it->get<bool>();
  }
  if (c.monotone_curves) {
    const auto form = json.find("monotone_form");
    if (form == json.end() || !form->is_string() || form->get<std::string>() != kMonotoneForm) {
      Fail("{}: tone mapper config: monotone curves of another construction ('monotone_form' "
           "{}, this version has \"{}\"): retrain the run",
           source, form == json.end() ? "missing: the earlier all-positive one" : form->dump(),
           kMonotoneForm);
    }
  }
  // Runs from before the key existed read unwritten bank rows as zeros.
  c.unseen_rows = json.contains("unseen_rows") ? ReadString(json, source, "unseen_rows") : "zero";
  const std::string problem = c.Validate();
  if (!problem.empty()) Fail("{}: tone mapper config: {}", source, problem);
  return c;
}

}  // namespace hdr4d::method
