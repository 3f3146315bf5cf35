#pragma once
/// Errors of viewcells: one exception type for bad input, carrying the file and line it came from.
#include <stdexcept>
#include <string>

namespace viewcells {

/// Thrown for bad input (missing or malformed files, non-finite coordinates, corrupt outputs)
/// and for failures of the libraries underneath (Embree). what() reads "file:line: message".
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message);
  /// line <= 0 means the position inside the file is unknown.
  Error(const std::string& file, long line, const std::string& message);

  const std::string& file() const { return file_; }
  long line() const { return line_; }

 private:
  std::string file_;
  long line_ = 0;
};

/// Always-on invariant check: throws std::logic_error naming the condition and place.
#define VC_CHECK(cond)                                                                    \
  do {                                                                                    \
    if (!(cond)) ::viewcells::detail::check_failed(#cond, __FILE__, __LINE__);            \
  } while (0)

namespace detail {
[[noreturn]] void check_failed(const char* cond, const char* file, int line);
}  // namespace detail

}  // namespace viewcells
