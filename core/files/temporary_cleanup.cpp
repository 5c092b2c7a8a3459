#include "core/files/temporary_cleanup.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <cstring>
#include <string>

namespace hdr4d {

namespace {

constexpr int kSlots = 256;
enum : int { kFree = 0, kFilling = 1, kSet = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX] = {};
};

Slot g_slots[kSlots];
std::atomic<bool> g_stopping{false};

void UnlinkTemporariesAndStop(int sig) {
  g_stopping.store(true);
  for (Slot& s : g_slots) {
    if (s.state.load() == kSet) ::unlink(s.path);  // async-signal-safe
  }
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

void RemoveTemporariesOnStopSignals() {
  static const bool installed = [] {
    struct sigaction action {};
    action.sa_handler = UnlinkTemporariesAndStop;
    sigemptyset(&action.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &action, nullptr);
    return true;
  }();
  (void)installed;
}

TrackedTemporary::TrackedTemporary(const std::filesystem::path& path) {
  const std::string& text = path.native();
  if (text.size() >= PATH_MAX || g_stopping.load()) return;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling)) continue;
    std::memcpy(g_slots[i].path, text.c_str(), text.size() + 1);
    g_slots[i].state.store(kSet);
    slot_ = i;
    return;
  }
}

TrackedTemporary::~TrackedTemporary() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree);
}

}  // namespace hdr4d
