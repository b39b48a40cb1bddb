#include "text_tokenizer.h"

#include <charconv>
#include <cmath>

#include "error.h"

namespace mpath {
namespace {

// What std::isspace calls white space in the "C" locale (mpath sets no
// other), without a call per character: OBJ parsing spent 5 % of a solve's
// start on that call.
constexpr bool is_space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

}  // namespace

void require_scene_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(fmt::format("{}: file not found", path.string()));
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(fmt::format("{}: not a regular file (a folder, device or pipe cannot be a scene file)", path.string()));
}

TextTokenizer::TextTokenizer(const std::filesystem::path& path) : path_(path.string()) {
  require_scene_file(path);
  in_.open(path);
  if (!in_) throw InputError(fmt::format("{}: cannot open file", path_));
}

std::string TextTokenizer::where() const { return fmt::format("{}:{}", path_, line_); }

void TextTokenizer::fail(const std::string& message) const { throw file_error(path_, line_, message); }

bool TextTokenizer::next(std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::string& raw = raw_;  // kept from line to line: no allocation per line
  while (true) {
    buffer_.clear();
    bool have = false;
    line_ = next_line_ + 1;
    while (std::getline(in_, raw)) {
      ++next_line_;
      have = true;
      if (!raw.empty() && raw.back() == '\r') raw.pop_back();
      if (const auto hash = raw.find('#'); hash != std::string::npos) raw.erase(hash);
      if (!raw.empty() && raw.back() == '\\') {
        raw.back() = ' ';
        buffer_ += raw;
        continue;
      }
      buffer_ += raw;
      break;
    }
    if (!have) return false;
    std::string_view s(buffer_);
    size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && is_space(s[i])) ++i;
      size_t j = i;
      while (j < s.size() && !is_space(s[j])) ++j;
      if (j > i) tokens.push_back(s.substr(i, j - i));
      i = j;
    }
    if (!tokens.empty()) return true;
  }
}

double TextTokenizer::number(std::string_view token, std::string_view what) const {
  double value = 0;
  const char* first = token.data();
  if (!token.empty() && token[0] == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), value);
  if (ec != std::errc() || ptr != token.data() + token.size())
    fail(fmt::format("expected a number for {}, got '{}'", what, token));
  if (!std::isfinite(value)) fail(fmt::format("expected a finite number for {}, got '{}'", what, token));
  return value;
}

long long TextTokenizer::integer(std::string_view token, std::string_view what) const {
  long long value = 0;
  const char* first = token.data();
  if (!token.empty() && token[0] == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), value);
  if (ec != std::errc() || ptr != token.data() + token.size())
    fail(fmt::format("expected an integer for {}, got '{}'", what, token));
  return value;
}

void TextTokenizer::expect_count(const std::vector<std::string_view>& tokens, size_t lo, size_t hi,
                              std::string_view usage) const {
  const size_t args = tokens.size() - 1;
  if (args < lo || args > hi) fail(fmt::format("malformed '{}': expected {}", tokens[0], usage));
}

}  // namespace mpath
