/// Ctrl-C and SIGTERM as a stop that long loops poll, so that no file is left half written.
#include "viewcells/core/interrupt.h"

#include <atomic>
#include <cmath>
#include <csignal>

namespace viewcells {

namespace {

std::atomic<int> g_requested{0};  // signals seen (lock-free: written from a signal handler)

extern "C" void on_signal(int signal) {
  if (g_requested.fetch_add(1) > 0) {  // the second one: as without a handler
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
}

}  // namespace

void install_interrupt_handlers() {
  static_assert(std::atomic<int>::is_always_lock_free);
  struct sigaction action = {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool interrupt_requested() { return g_requested.load(std::memory_order_relaxed) > 0; }

void throw_if_interrupted(const char* what) {
  if (interrupt_requested()) throw Interrupted(std::string(what) + ": interrupted (Ctrl-C or SIGTERM); nothing was written");
}

void request_interrupt(bool on) { g_requested.store(on ? 1 : 0); }

Deadline Deadline::after(double seconds) {
  Deadline d;
  if (seconds > 0 && seconds < 1e9)
    d.at = std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
  return d;
}

}  // namespace viewcells
