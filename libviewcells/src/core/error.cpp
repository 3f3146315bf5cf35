/// The one exception type for bad input, naming the file and line.
#include "viewcells/core/error.h"

#include <stdexcept>

namespace viewcells {
namespace {
std::string format_position(const std::string& file, long line, const std::string& message) {
  if (file.empty()) return message;
  if (line <= 0) return file + ": " + message;
  return file + ":" + std::to_string(line) + ": " + message;
}
}  // namespace

Error::Error(const std::string& message) : std::runtime_error(message) {}

Error::Error(const std::string& file, long line, const std::string& message)
    : std::runtime_error(format_position(file, line, message)), file_(file), line_(line) {}

namespace detail {
void check_failed(const char* cond, const char* file, int line) {
  throw std::logic_error(std::string("internal check failed: ") + cond + " at " + file + ":" +
                         std::to_string(line));
}
}  // namespace detail

}  // namespace viewcells
