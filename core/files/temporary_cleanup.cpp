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

// Beyond the fixed slots (a video's thousands of frames wait for one commit): nodes allocated
// outside the handler, pushed onto a list that only grows and is never freed, so the handler
// can walk it without allocating; a released node is reused by a later path that fits it.
struct OverflowNode {
  std::atomic<int> state{kFilling};
  std::size_t capacity = 0;
  char* path = nullptr;
  OverflowNode* next = nullptr;
};
std::atomic<OverflowNode*> g_overflow{nullptr};
std::atomic<int> g_free_nodes{0};  // released nodes: the list is searched only when some are

OverflowNode* TakeOverflowNode(const std::string& text) {
  for (OverflowNode* n = g_free_nodes.load() > 0 ? g_overflow.load() : nullptr; n != nullptr;
       n = n->next) {
    int expected = kFree;
    if (n->capacity > text.size() && n->state.compare_exchange_strong(expected, kFilling)) {
      g_free_nodes.fetch_sub(1);
      std::memcpy(n->path, text.c_str(), text.size() + 1);
      n->state.store(kSet);
      return n;
    }
  }
  auto* n = new OverflowNode;
  n->capacity = text.size() + 1;
  n->path = new char[n->capacity];
  std::memcpy(n->path, text.c_str(), text.size() + 1);
  n->state.store(kSet);
  n->next = g_overflow.load();
  while (!g_overflow.compare_exchange_weak(n->next, n)) {
  }
  return n;
}

void UnlinkTemporariesAndStop(int sig) {
  g_stopping.store(true);
  for (Slot& s : g_slots) {
    if (s.state.load() == kSet) ::unlink(s.path);  // async-signal-safe
  }
  for (OverflowNode* n = g_overflow.load(); n != nullptr; n = n->next) {
    if (n->state.load() == kSet) ::unlink(n->path);
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
  overflow_ = TakeOverflowNode(text);
}

TrackedTemporary::~TrackedTemporary() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree);
  if (overflow_) {
    static_cast<OverflowNode*>(overflow_)->state.store(kFree);
    g_free_nodes.fetch_add(1);
  }
}

}  // namespace hdr4d
