#include "progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace mpath {
namespace {
std::atomic<bool> g_enabled{true};

std::string duration(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  const int t = static_cast<int>(s + 0.5);
  if (t >= 3600) return fmt::format("{}h{:02}m", t / 3600, (t / 60) % 60);
  if (t >= 60) return fmt::format("{}m{:02}s", t / 60, t % 60);
  return fmt::format("{}s", t);
}

std::string rate(double per_second) {
  if (per_second >= 1e6) return fmt::format("{:.2f}M", per_second / 1e6);
  if (per_second >= 1e3) return fmt::format("{:.1f}k", per_second / 1e3);
  return fmt::format("{:.0f}", per_second);
}
}  // namespace

void Progress::set_enabled_default(bool enabled) { g_enabled = enabled; }
bool Progress::enabled_default() { return g_enabled; }

Progress::Progress(std::string label, uint64_t total, std::string unit, bool enabled)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), enabled_(enabled && g_enabled),
      tty_(isatty(STDERR_FILENO) != 0), start_(std::chrono::steady_clock::now()), last_print_(start_) {}

Progress::~Progress() { finish(); }

void Progress::advance(uint64_t n) {
  const uint64_t done = done_.fetch_add(n) + n;
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  const double interval = tty_ ? 0.2 : 10.0;
  if (std::chrono::duration<double>(now - last_print_).count() < interval) return;
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  last_print_ = now;
  print(done, false);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (enabled_) print(done_.load(), true);
}

void Progress::print(uint64_t done, bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double fraction = total_ ? std::min(1.0, static_cast<double>(done) / static_cast<double>(total_)) : 1.0;
  const double per_second = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  const double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : -1;
  if (tty_) {
    const int width = 30, filled = static_cast<int>(fraction * width);
    fmt::print(stderr, "\r{} [{}{}] {:5.1f}% {} {}/s ETA {}   ", label_, std::string(filled, '#'),
               std::string(width - filled, '.'), 100 * fraction, rate(per_second), unit_, duration(eta));
    if (final) fmt::print(stderr, "\r{} done: {} {} in {} ({} {}/s){}\n", label_, done, unit_, duration(elapsed),
                          rate(per_second), unit_, std::string(20, ' '));
  } else if (final) {
    fmt::print(stderr, "{} done: {} {} in {} ({} {}/s)\n", label_, done, unit_, duration(elapsed), rate(per_second), unit_);
  } else {
    fmt::print(stderr, "{}: {:.1f}% ({} {}/s, ETA {})\n", label_, 100 * fraction, rate(per_second), unit_, duration(eta));
  }
  std::fflush(stderr);
}

}  // namespace mpath
