/// Thread control: how many cores stages use (never what they compute).
#include "viewcells/core/parallel.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "viewcells/core/ranks.h"

namespace viewcells {

struct ThreadLimit::Impl {
  explicit Impl(int n) : control(tbb::global_control::max_allowed_parallelism, n) {}
  tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads)
    : threads_(threads > 0 ? threads : hardware_threads()) {
  impl_ = std::make_unique<Impl>(threads_);
}

ThreadLimit::~ThreadLimit() = default;

int hardware_threads() { return tbb::info::default_concurrency(); }

int worker_threads() {
  return static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

std::string workers_text() {
  const int t = worker_threads(), r = ranks::size();
  const std::string threads = std::to_string(t) + (t == 1 ? " thread" : " threads");
  return r > 1 ? std::to_string(r) + " ranks of " + threads : threads;
}

}  // namespace viewcells
