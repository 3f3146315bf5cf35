/// Progress bars on stderr for long stages, thread-safe and silent off a terminal.
#include "viewcells/core/progress.h"

#include "viewcells/core/ranks.h"

#include <unistd.h>

#include <cstdio>

namespace viewcells {

Progress::Progress(std::string label, uint64_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(isatty(STDERR_FILENO) == 1 && ranks::writer()),  // one bar per run, from rank 0
      start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
  // A bar that was never advanced nor finished was switched off by its caller (a quiet run
  // guards advance() and finish() by its show-progress flag): it draws nothing.
  if (!finished_ && done_.load() > 0) finish();
}

void Progress::advance(uint64_t n) {
  const uint64_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
  if (!enabled_) return;
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::steady_clock::now() - start_)
                          .count();
  int64_t last = last_draw_ns_.load(std::memory_order_relaxed);
  if (now - last < 100'000'000) return;
  if (!last_draw_ns_.compare_exchange_strong(last, now)) return;  // another thread draws
  std::unique_lock lock(draw_mutex_, std::try_to_lock);
  if (lock.owns_lock()) draw(done, false);
}

void Progress::set_status(std::string status) {
  std::lock_guard lock(status_mutex_);
  status_ = std::move(status);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  std::lock_guard lock(draw_mutex_);
  draw(done_.load(), true);
}

void Progress::draw(uint64_t done, bool final) {
  constexpr int kWidth = 30;
  const double frac = total_ ? std::min(1.0, static_cast<double>(done) / total_) : 1.0;
  const int filled = static_cast<int>(frac * kWidth);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  const double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
  std::string status;
  {
    std::lock_guard lock(status_mutex_);
    status = status_;
  }
  if (total_ == 0) {
    std::fprintf(stderr, "\r%-12s %llu done  %.1fs elapsed  %s   ", label_.c_str(),
                 static_cast<unsigned long long>(done), elapsed, status.c_str());
  } else {
    std::fprintf(stderr, "\r%-12s [%s] %5.1f%%  %.1fs elapsed, %.1fs left  %s   ", label_.c_str(), bar,
                 100.0 * frac, elapsed, final ? 0.0 : eta, status.c_str());
  }
  if (final) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace viewcells
