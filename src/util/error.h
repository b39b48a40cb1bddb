// Errors: InputError for bad user input (scene, config, store) carrying where it
// is; MPATH_CHECK for internal invariants, which abort with file:line.
#pragma once

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace mpath {

// Bad input from the user. what() is the full one-line message shown on stderr.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

// An error located in a file: "path:line: message".
inline InputError file_error(const std::string& path, long line, const std::string& message) {
  if (line > 0) return InputError(fmt::format("{}:{}: {}", path, line, message));
  return InputError(fmt::format("{}: {}", path, message));
}

// `text` fit for a terminal and a log: bytes that are not printable UTF-8
// (a damaged file quoted in a message) become \xNN.
std::string printable(const std::string& text);

[[noreturn]] void check_failed(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace mpath

#define MPATH_CHECK(cond, ...)                                                          \
  do {                                                                                  \
    if (!(cond)) ::mpath::check_failed(#cond, __FILE__, __LINE__, fmt::format(__VA_ARGS__)); \
  } while (0)
