#include "baselines/hexplane/hexplane_train_state.h"

#include <cstring>
#include <fstream>

#include "baselines/hexplane/binary_io.h"
#include "core/files/atomic_file.h"
#include "core/util/error.h"

namespace hdr4d::baselines::hexplane {
namespace {
constexpr char kStateMagic[8] = {'H', 'X', 'T', 'R', 'A', 'I', 'N', '1'};
constexpr std::uint64_t kMaxRngText = 1 << 16;  // mt19937_64's text is ~6 KB
}  // namespace

void SaveTrainingCheckpoint(const std::filesystem::path& file, const HexPlaneModel& model,
                            const PlainAdam& adam, const HexPlaneTrainState& state) {
  WriteFileAtomic(file, [&](std::ostream& out) {
    model.Write(out);
    out.write(kStateMagic, sizeof kStateMagic);
    WritePod(out, state.iteration);
    WritePod(out, state.seconds);
    WritePod(out, state.epoch_seed);
    WritePod(out, state.next);
    WritePod(out, std::uint8_t(state.in_epoch));
    WritePod(out, std::uint64_t(state.rng.size()));
    out.write(state.rng.data(), std::streamsize(state.rng.size()));
    WriteArray(out, state.curve);
    adam.Write(out);
  });
}

HexPlaneTrainState LoadTrainingCheckpoint(const std::filesystem::path& file,
                                          const HexPlaneConfig& config, HexPlaneModel* model,
                                          PlainAdam* adam) {
  std::ifstream in(file, std::ios::binary);
  if (!in) Fail("{}: cannot open the HexPlane checkpoint", file.string());
  *model = HexPlaneModel::Read(in, file, config);
  const std::string name = file.string();
  char magic[8];
  in.read(magic, sizeof magic);
  if (!in || std::memcmp(magic, kStateMagic, sizeof magic) != 0)
    Fail("{}: holds no training state to resume from (a model only, or cut short)", name);
  HexPlaneTrainState s;
  s.iteration = ReadPod<std::int64_t>(in, name, "the iteration");
  s.seconds = ReadPod<double>(in, name, "the training time");
  s.epoch_seed = ReadPod<std::uint64_t>(in, name, "the pixel order");
  s.next = ReadPod<std::uint64_t>(in, name, "the pixel order");
  s.in_epoch = ReadPod<std::uint8_t>(in, name, "the pixel order") != 0;
  const auto rng_size = ReadPod<std::uint64_t>(in, name, "the random generator");
  if (s.iteration < 0 || !(s.seconds >= 0) || rng_size > kMaxRngText)
    Fail("{}: bad training state (iteration {}, {} s)", name, s.iteration, s.seconds);
  s.rng.resize(rng_size);
  in.read(s.rng.data(), std::streamsize(rng_size));
  if (!in) Fail("{}: cut short in the random generator", name);
  ReadArrayOfAnyLength(in, std::uint64_t{3} << 24, name, "the training curve", &s.curve);
  if (s.curve.size() % 3 != 0) Fail("{}: the training curve is not in triples", name);
  adam->Read(in, name);
  if (in.peek() != std::char_traits<char>::eof()) Fail("{}: unexpected bytes at the end", name);
  return s;
}

}  // namespace hdr4d::baselines::hexplane
