#include "method/train/checkpoint.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <streambuf>
#include <string_view>

#include "core/files/binary_stream.h"
#include "core/files/file_access.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'H', 'D', 'R', '4', 'D', 'C', 'K', 'P'};
// Version 2 adds the tone mapper's state after the optimiser's; version 3 a trailer with a
// checksum of every byte before it, so damage inside the float buffers (which no size check
// can see) is refused instead of rendered. Versions 1 and 2 still load.
constexpr std::uint32_t kVersion = 3;
constexpr char kTrailerMagic[8] = {'H', 'D', 'R', '4', 'D', 'S', 'U', 'M'};
constexpr std::size_t kTrailerSize = 16;

void WriteU64(std::ostream& out, std::uint64_t v) {
  out.write(reinterpret_cast<const char*>(&v), 8);
}

std::uint64_t ReadU64(std::istream& in, const fs::path& path, const char* what) {
  std::uint64_t v = 0;
  if (!in.read(reinterpret_cast<char*>(&v), 8))
    Fail("{}: truncated checkpoint (while reading {})", path.string(), what);
  return v;
}

std::vector<float> ReadFloats(std::istream& in,
                              const fs::path& path,
                              const char* what,
                              std::uint64_t limit) {
  const std::uint64_t n = ReadU64(in, path, what);
  if (n > limit) Fail("{}: corrupt checkpoint ({} claims {} values)", path.string(), what, n);
  std::vector<float> v(n);
  if (!in.read(reinterpret_cast<char*>(v.data()),
               static_cast<std::streamsize>(n * sizeof(float)))) {
    Fail("{}: truncated checkpoint (while reading {})", path.string(), what);
  }
  return v;
}

void RequireFiniteValues(const std::vector<float>& v, const fs::path& path, const char* what) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      Fail("{}: corrupt checkpoint: {} holds {} at value {} of {}", path.string(), what, v[i], i,
           v.size());
    }
  }
}

// The model's buffers in file order.
template <typename Model, typename Fn>
void ForEachBuffer(Model& m, Fn&& fn) {
  fn("xyz", m.xyz);
  fn("t", m.t);
  fn("log_scales", m.log_scales);
  fn("rot_left", m.rot_left);
  fn("rot_right", m.rot_right);
  fn("opacity_logit", m.opacity_logit);
  fn("color_dc", m.color_dc);
  fn("color_rest", m.color_rest);
}

// An output stream that appends to a HashingWriter and counts what it took, so a section's
// writer can use the std::ostream interface of the state formats (Adam::Save).
class HashingStreamBuf : public std::streambuf {
 public:
  explicit HashingStreamBuf(HashingWriter* out) : out_(out) {}
  std::uint64_t written() const { return written_; }

 protected:
  std::streamsize xsputn(const char* data, std::streamsize n) override {
    out_->Bytes(data, static_cast<std::size_t>(n));
    written_ += static_cast<std::uint64_t>(n);
    return n;
  }
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char ch = traits_type::to_char_type(c);
    return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
  }

 private:
  HashingWriter* out_;
  std::uint64_t written_ = 0;
};

// A read-only stream over bytes already in memory, without the copy istringstream makes.
class MemoryStreamBuf : public std::streambuf {
 public:
  MemoryStreamBuf(char* data, std::size_t size) { setg(data, data, data + size); }
};

void WriteSection(const CheckpointSection& section, const char* what, HashingWriter* out) {
  out->Value<std::uint64_t>(section.size);
  if (section.size == 0) return;
  HashingStreamBuf buf(out);
  std::ostream stream(&buf);
  section.write(stream);
  // A size that disagrees with the bytes would make the file unreadable: the write is abandoned
  // (the previous checkpoint stays).
  if (buf.written() != section.size) {
    Fail("checkpoint {} section: {} bytes announced, {} written", what, section.size,
         buf.written());
  }
}

}  // namespace

CheckpointSection CheckpointSection::Of(std::string_view bytes) {
  return {bytes.size(), [bytes](std::ostream& out) {
            out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
          }};
}

CheckpointSection CheckpointSection::Of(const Adam& adam) {
  return {adam.SavedSize(), [&adam](std::ostream& out) { adam.Save(out); }};
}

void SaveCheckpoint(const fs::path& path, const CheckpointParts& p) {
  HDR4D_CHECK(p.model != nullptr && p.trainer != nullptr);
  const GaussianModel& model = *p.model;
  HDR4D_CHECK(model.Validate().empty());
  nlohmann::json header = {
      {"version", kVersion},
      {"temporal", model.temporal},
      {"color_mode", model.color_mode == ColorMode::kLdr ? "ldr" : "log_hdr"},
      {"max_sh_degree", model.basis.max_sh_degree},
      {"max_time_degree", model.basis.max_time_degree},
      {"channels", model.channels},
      {"gaussians", model.size()},
      {"trainer", *p.trainer},
  };
  // Streamed into the file with a running checksum, from the live state: building the bytes in
  // memory first (a copy of the model, the optimiser state as a string, a growing string stream of
  // the file) added ~4 KB per Gaussian to the peak of every run
  // (docs/history/paper-configuration.md).
  WriteFileAtomic(path, [&](std::ostream& file) {
    HashingWriter out(file);
    const auto floats = [&](const std::vector<float>& v) {
      out.Value<std::uint64_t>(v.size());
      out.Bytes(v.data(), v.size() * sizeof(float));
    };
    out.Bytes(kMagic, sizeof(kMagic));
    const std::string text = header.dump();
    out.Value<std::uint64_t>(text.size());
    out.Bytes(text.data(), text.size());
    ForEachBuffer(model, [&](const char*, const std::vector<float>& v) { floats(v); });
    out.Value<std::uint64_t>(p.extra_floats.size());
    for (const std::vector<float>* v : p.extra_floats) floats(*v);
    WriteSection(p.adam_state, "optimiser", &out);
    WriteSection(p.tone_mapper_state, "tone mapper", &out);
    file.write(kTrailerMagic, sizeof(kTrailerMagic));
    WriteU64(file, out.hash());
  });
}

void SaveCheckpoint(const fs::path& path, const Checkpoint& c) {
  CheckpointParts parts{.model = &c.model,
                        .trainer = &c.trainer,
                        .adam_state = CheckpointSection::Of(c.adam_state),
                        .tone_mapper_state = CheckpointSection::Of(c.tone_mapper_state)};
  for (const std::vector<float>& v : c.extra_floats) parts.extra_floats.push_back(&v);
  SaveCheckpoint(path, parts);
}

namespace {

// The whole file in one buffer of its size, to be parsed in place: copying through string
// streams held the file four times over (rdbuf into a growing buffer, str(), istringstream),
// 1.5 GB of a 0.4 GB checkpoint at the peak, and took most of `hdr4d render`'s start-up.
std::unique_ptr<char[]> ReadWholeFile(const fs::path& path, std::size_t* size) {
  std::error_code ec;
  if (!fs::exists(path, ec)) Fail("{}: checkpoint not found", path.string());
  RequireInputFile(path);  // a device or FIFO is refused before it is opened
  std::ifstream file(path, std::ios::binary);
  if (!file) Fail("{}: cannot open for reading", path.string());
  const std::uintmax_t expected = fs::file_size(path, ec);
  if (ec) Fail("{}: cannot read its size: {}", path.string(), ec.message());
  // Not zero-filled first: the read writes every byte.
  auto buffer = std::make_unique_for_overwrite<char[]>(static_cast<std::size_t>(expected));
  *size = static_cast<std::size_t>(expected);
  if (!file.read(buffer.get(), static_cast<std::streamsize>(*size)))
    Fail("{}: truncated checkpoint (the file shrank while it was read)", path.string());
  return buffer;
}

// The magic and the JSON header; `in` is left at the model's first buffer.
nlohmann::json ReadHeader(std::istream& in,
                          const fs::path& path,
                          std::uint64_t file_size,
                          std::uint64_t* header_size) {
  char magic[8] = {};
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0)
    Fail("{}: not an hdr4d checkpoint", path.string());
  *header_size = ReadU64(in, path, "the header size");
  if (*header_size > file_size) Fail("{}: corrupt checkpoint header", path.string());
  std::string text(*header_size, '\0');
  if (!in.read(text.data(), static_cast<std::streamsize>(*header_size)))
    Fail("{}: truncated checkpoint header", path.string());
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: corrupt checkpoint header: {}", path.string(), e.what());
  }
}

// The header's model layout and trainer state into `c`; returns the file's version.
std::uint32_t ApplyHeader(const nlohmann::json& header, const fs::path& path, Checkpoint* c) {
  std::uint32_t version = 0;
  try {
    version = header.at("version").get<std::uint32_t>();
    if (version < 1 || version > kVersion) {
      Fail("{}: checkpoint version {} is not supported (this build reads {})", path.string(),
           header.at("version").get<std::uint32_t>(), kVersion);
    }
    c->model.temporal = header.at("temporal").get<bool>();
    c->model.color_mode =
        header.at("color_mode").get<std::string>() == "ldr" ? ColorMode::kLdr : ColorMode::kLogHdr;
    c->model.basis.max_sh_degree = header.at("max_sh_degree").get<int>();
    c->model.basis.max_time_degree = header.at("max_time_degree").get<int>();
    c->model.channels = header.at("channels").get<int>();
    c->trainer = header.at("trainer");
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: checkpoint header is missing a key: {}", path.string(), e.what());
  }
  return version;
}

// Where an intact checkpoint ends inside `bytes` that do not end with its trailer: the end of
// the last trailer whose checksum matches the bytes before it, or 0 (then the file is truncated
// or its end damaged, not appended to). Looks at the last 16 trailer magics at most.
std::size_t IntactCheckpointEnd(std::string_view bytes, std::uint64_t header_size) {
  const std::string_view magic(kTrailerMagic, 8);
  std::size_t at = bytes.size() >= kTrailerSize ? bytes.size() - kTrailerSize : 0;
  for (int tries = 0; tries < 16; ++tries) {
    at = bytes.rfind(magic, at);
    if (at == std::string_view::npos || at < header_size) return 0;
    std::uint64_t stored = 0;
    std::memcpy(&stored, bytes.data() + at + 8, 8);
    if (stored == Fnv1a(bytes.data(), at)) return at + kTrailerSize;
    if (at == 0) return 0;
    --at;
  }
  return 0;
}

// Version 3's trailer: the checksum of every byte before it.
void VerifyChecksum(std::string_view bytes, std::uint64_t header_size, const fs::path& path) {
  const std::size_t body = bytes.size() >= kTrailerSize ? bytes.size() - kTrailerSize : 0;
  std::uint64_t stored = 0;
  if (body < header_size || std::memcmp(bytes.data() + body, kTrailerMagic, 8) != 0) {
    if (const std::size_t end = IntactCheckpointEnd(bytes, header_size); end > 0) {
      Fail("{}: corrupt checkpoint: {} bytes were appended after its end (the checkpoint is "
           "intact up to byte {}; something wrote to the file after hdr4d did)",
           path.string(), bytes.size() - end, end);
    }
    Fail("{}: truncated checkpoint (its checksum trailer is missing)", path.string());
  }
  std::memcpy(&stored, bytes.data() + body + 8, 8);
  if (stored != Fnv1a(bytes.data(), body)) {
    Fail("{}: corrupt checkpoint (checksum mismatch: the file was damaged after it was written)",
         path.string());
  }
}

// After the header: the model's buffers, the extra float buffers, the optimiser's state (kept
// or skipped as `options` says) and, from version 2, the tone mapper's.
void ReadBody(std::istream& in,
              const fs::path& path,
              std::uint64_t file_size,
              std::uint32_t version,
              const CheckpointLoadOptions& options,
              Checkpoint* c) {
  const std::uint64_t limit = file_size / sizeof(float);
  ForEachBuffer(c->model, [&](const char* name, std::vector<float>& v) {
    v = ReadFloats(in, path, name, limit);
  });
  const std::uint64_t extras = ReadU64(in, path, "the extra buffer count");
  if (extras > 64) Fail("{}: corrupt checkpoint ({} extra buffers)", path.string(), extras);
  for (std::uint64_t i = 0; i < extras; ++i)
    c->extra_floats.push_back(ReadFloats(in, path, "an extra buffer", limit));
  const std::uint64_t adam_size = ReadU64(in, path, "the optimiser state size");
  if (adam_size > file_size) Fail("{}: corrupt checkpoint (optimiser state size)", path.string());
  if (options.optimizer_state) {
    c->adam_state.resize(adam_size);
    in.read(c->adam_state.data(), static_cast<std::streamsize>(adam_size));
  } else {
    in.ignore(static_cast<std::streamsize>(adam_size));
  }
  if (!in || static_cast<std::uint64_t>(in.gcount()) != adam_size)
    Fail("{}: truncated checkpoint (while reading the optimiser state)", path.string());
  if (version < 2) return;
  const std::uint64_t tm_size = ReadU64(in, path, "the tone mapper state size");
  if (tm_size > file_size) Fail("{}: corrupt checkpoint (tone mapper state size)", path.string());
  c->tone_mapper_state.resize(tm_size);
  if (!in.read(c->tone_mapper_state.data(), static_cast<std::streamsize>(tm_size))) {
    Fail("{}: truncated checkpoint (while reading the tone mapper state)", path.string());
  }
}

// Values, not only sizes: a model with NaN or Inf in it is never resumed or rendered (version
// 1-2 files have no checksum, and a writer bug could store them).
void CheckLoadedValues(const Checkpoint& c, const nlohmann::json& header, const fs::path& path) {
  ForEachBuffer(c.model, [&](const char* name, const std::vector<float>& v) {
    RequireFiniteValues(v, path, name);
  });
  for (const std::vector<float>& v : c.extra_floats)
    RequireFiniteValues(v, path, "the densification statistics");
  if (const std::string problem = c.model.Validate(); !problem.empty()) {
    Fail("{}: inconsistent checkpoint: {}", path.string(), problem);
  }
  if (c.model.size() != header.value("gaussians", std::size_t{0})) {
    Fail("{}: inconsistent checkpoint: header says {} Gaussians, buffers hold {}", path.string(),
         header.value("gaussians", std::size_t{0}), c.model.size());
  }
}

}  // namespace

Checkpoint LoadCheckpoint(const fs::path& path, const CheckpointLoadOptions& options) {
  std::size_t size = 0;
  const std::unique_ptr<char[]> buffer = ReadWholeFile(path, &size);
  const std::string_view bytes(buffer.get(), size);
  MemoryStreamBuf view(buffer.get(), bytes.size());
  std::istream in(&view);
  std::uint64_t header_size = 0;
  const nlohmann::json header = ReadHeader(in, path, bytes.size(), &header_size);
  Checkpoint c;
  const std::uint32_t version = ApplyHeader(header, path, &c);
  if (version >= 3) VerifyChecksum(bytes, header_size, path);
  ReadBody(in, path, bytes.size(), version, options, &c);
  CheckLoadedValues(c, header, path);
  return c;
}

}  // namespace hdr4d::method
