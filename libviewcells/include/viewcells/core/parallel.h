#pragma once
/// Thread control. Stages are written so that their output never depends on the thread count;
/// this only bounds how many cores they use.
#include <memory>
#include <string>

namespace viewcells {

/// While alive, limits every parallel stage (TBB and Embree's TBB tasks) to `threads` threads.
/// threads == 0 means all hardware threads.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;
  /// The number of threads in effect.
  int threads() const { return threads_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int threads_;
};

/// Number of hardware threads.
int hardware_threads();
/// Threads parallel stages use now (the innermost ThreadLimit's, else all hardware threads).
int worker_threads();
/// What this run works on, for log lines: "2 threads", or on a cluster "3 ranks of 2 threads".
std::string workers_text();

}  // namespace viewcells
