// Progress of long work on stderr: a bar on a terminal, otherwise a plain
// line (percent, rate, ETA) every few seconds. Thread-safe `advance`.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace mpath {

class Progress {
 public:
  // `enabled` false (--quiet) prints nothing.
  Progress(std::string label, uint64_t total, std::string unit, bool enabled);
  ~Progress();
  void advance(uint64_t n);
  void finish();

  static void set_enabled_default(bool enabled);
  static bool enabled_default();

 private:
  void print(uint64_t done, bool final);

  std::string label_, unit_;
  uint64_t total_;
  bool enabled_, tty_;
  std::atomic<uint64_t> done_{0};
  std::chrono::steady_clock::time_point start_, last_print_;
  std::mutex mutex_;
  bool finished_ = false;
};

}  // namespace mpath
