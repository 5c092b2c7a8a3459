// Progress for every long command: a redrawn bar on a terminal, plain lines (at most one per
// `log_every` of the total) when stderr is a log file or a pipe.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace hdr4d {

class Progress {
 public:
  // total: number of steps; label: what is being done ("render", "train").
  Progress(std::string label, std::int64_t total, bool enabled = true);
  ~Progress();

  // Advance by `steps`; `status` is shown after the counter (loss, PSNR, ...). Thread-safe.
  void Advance(std::int64_t steps = 1, const std::string& status = "");
  void SetStatus(const std::string& status);
  // Final line with the elapsed time; called by the destructor if not called before.
  void Finish();

  double ElapsedSeconds() const;

 private:
  void Draw(bool final_line);

  std::string label_;
  std::int64_t total_;
  std::int64_t done_ = 0;
  bool enabled_;
  bool tty_;
  bool finished_ = false;
  int last_logged_bucket_ = -1;
  std::int64_t last_logged_done_ = -1;
  std::string status_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  std::mutex mutex_;
};

}  // namespace hdr4d
