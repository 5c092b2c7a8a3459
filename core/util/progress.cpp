#include "core/util/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace hdr4d {

Progress::Progress(std::string label, std::int64_t total, bool enabled)
    : label_(std::move(label)),
      total_(std::max<std::int64_t>(total, 1)),
      enabled_(enabled),
      tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { Finish(); }

double Progress::ElapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::Advance(std::int64_t steps, const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = std::min(total_, done_ + steps);
  if (!status.empty()) status_ = status;
  Draw(false);
}

void Progress::SetStatus(const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  status_ = status;
}

void Progress::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  Draw(true);
}

void Progress::Draw(bool final_line) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const int percent = static_cast<int>(100 * done_ / total_);
  const double rate = elapsed > 0 ? done_ / elapsed : 0.0;
  const std::string counter =
      fmt::format("{} {}/{} ({}%) {:.1f}/s {:.1f}s", label_, done_, total_, percent, rate, elapsed);
  if (tty_) {
    // Redraw at most 10 times a second.
    if (!final_line && now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
    last_draw_ = now;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(kWidth * done_ / total_);
    std::fprintf(stderr, "\r[%s%s] %s %s\x1b[K", std::string(filled, '#').c_str(),
                 std::string(kWidth - filled, ' ').c_str(), counter.c_str(), status_.c_str());
    if (final_line) std::fputc('\n', stderr);
  } else {
    // A log gets a line each time another tenth is done, and a final one unless the last line
    // already showed the same count.
    const int bucket = percent / 10;
    if (!final_line && bucket == last_logged_bucket_) return;
    if (final_line && done_ == last_logged_done_) return;
    last_logged_bucket_ = bucket;
    last_logged_done_ = done_;
    std::fprintf(stderr, "%s %s\n", counter.c_str(), status_.c_str());
  }
  std::fflush(stderr);
}

}  // namespace hdr4d
