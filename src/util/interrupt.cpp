#include "interrupt.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

namespace mpath {
namespace {

// Fixed slots: a signal handler may only touch what was set up beforehand.
constexpr int kSlots = 64;
constexpr size_t kPathBytes = 4096;
char g_paths[kSlots][kPathBytes];
// 0 free, 1 being written, 2 holds a path the handler may remove.
std::atomic<int> g_state[kSlots];
const char* g_program = "mpath";
const char* g_advice = "";

void write_all(const char* s) {
  size_t n = std::strlen(s);
  while (n > 0) {
    const ssize_t w = write(STDERR_FILENO, s, n);
    if (w <= 0) return;
    s += w;
    n -= static_cast<size_t>(w);
  }
}

void on_signal(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_state[i].load() == 2) unlink(g_paths[i]);
  write_all("\n");
  write_all(g_program);
  write_all(": interrupted; ");
  write_all(g_advice);
  write_all("\n");
  _exit(128 + sig);
}

}  // namespace

void install_interrupt_handlers(const char* program, const char* advice) {
  g_program = program;
  g_advice = advice;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int remember_temporary(const std::filesystem::path& path) {
  const std::string s = path.string();
  if (s.size() >= kPathBytes) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (!g_state[i].compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_paths[i], s.c_str(), s.size() + 1);
    g_state[i].store(2);  // only a complete path is ever removed
    return i;
  }
  return -1;
}

void forget_temporary(int slot) {
  if (slot >= 0) g_state[slot].store(0);
}

}  // namespace mpath
