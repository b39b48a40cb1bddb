// Splits a text scene file (OBJ, MTL, MGF) into tokens a logical line at a
// time, with strict number parsing and errors that carry file:line.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace mpath {

// Throws InputError unless `path` is an existing regular file (a folder, a
// device such as /dev/zero or a pipe cannot be a scene file).
void require_scene_file(const std::filesystem::path& path);

class TextTokenizer {
 public:
  // Throws InputError when the file cannot be opened.
  explicit TextTokenizer(const std::filesystem::path& path);

  // Next line with at least one token ('#' starts a comment, a trailing
  // backslash continues the line). False at end of file.
  bool next(std::vector<std::string_view>& tokens);

  long line() const { return line_; }
  const std::string& path() const { return path_; }
  std::string where() const;

  [[noreturn]] void fail(const std::string& message) const;
  double number(std::string_view token, std::string_view what) const;  // finite, or fail
  long long integer(std::string_view token, std::string_view what) const;
  void expect_count(const std::vector<std::string_view>& tokens, size_t lo, size_t hi,
                    std::string_view usage) const;

 private:
  std::ifstream in_;
  std::string path_;
  std::string buffer_;
  std::string raw_;  // the physical line being read
  long line_ = 0;
  long next_line_ = 0;
};

}  // namespace mpath
