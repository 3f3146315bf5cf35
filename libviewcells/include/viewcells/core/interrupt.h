#pragma once
/// A stop the user asked for (Ctrl-C: SIGINT, or SIGTERM). Long loops (frames, AGVS batches,
/// sampling batches) poll it between units of work and throw Interrupted, so that a command
/// ends with an error and every file it would have written stays as it was (outputs are
/// renamed into place only when the whole command succeeded). The flag is process-wide by
/// nature: a signal has no other place to go.
#include <chrono>
#include <string>

#include "viewcells/core/error.h"

namespace viewcells {

/// Thrown where a loop sees the stop asked for.
class Interrupted : public Error {
 public:
  using Error::Error;
};

/// Installs the handlers for SIGINT and SIGTERM (the CLI does, once). The first signal asks
/// loops to stop; a second one ends the process at once, as without the handler.
void install_interrupt_handlers();
/// True once a stop was asked for (or request_interrupt was called).
bool interrupt_requested();
/// Throws Interrupted naming `what` (the stage) when a stop was asked for. Cheap: one atomic load.
void throw_if_interrupted(const char* what);
/// Asks for a stop, or takes the request back (tests).
void request_interrupt(bool on = true);

/// A stop by the clock (a bake's --time): loops that can end early with a partial result they
/// state (frames measured, frames sampled) poll it between units of work. Default: none.
struct Deadline {
  std::chrono::steady_clock::time_point at = std::chrono::steady_clock::time_point::max();
  /// `seconds` from now; none when seconds <= 0 or not finite.
  static Deadline after(double seconds);
  bool set() const { return at != std::chrono::steady_clock::time_point::max(); }
  bool passed() const { return set() && std::chrono::steady_clock::now() >= at; }
};

}  // namespace viewcells
