#pragma once
/// A progress bar on stderr for long stages. Silent unless stderr is a terminal (or forced),
/// thread-safe: workers call advance(); only one thread redraws, at most ten times a second.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace viewcells {

class Progress {
 public:
  /// total: units of work (0: unknown, a counter instead of a bar); label: shown before the
  /// bar. Enabled when stderr is a TTY.
  Progress(std::string label, uint64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(uint64_t n = 1);
  /// Text shown after the bar (e.g. a running estimate); thread-safe.
  void set_status(std::string status);
  /// Draws the final state and ends the line.
  void finish();
  bool enabled() const { return enabled_; }

 private:
  void draw(uint64_t done, bool final);

  std::string label_;
  uint64_t total_;
  bool enabled_;
  bool finished_ = false;
  std::atomic<uint64_t> done_{0};
  std::atomic<int64_t> last_draw_ns_{0};
  std::mutex draw_mutex_;
  std::mutex status_mutex_;
  std::string status_;
  std::chrono::steady_clock::time_point start_;
};

/// Wall-clock stopwatch in seconds.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  void restart() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace viewcells
