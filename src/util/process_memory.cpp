#include "process_memory.h"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif

namespace mpath {

size_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<size_t>(usage.ru_maxrss) * 1024;
}

void keep_freed_memory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);   // blocks up to 32 MiB from the heap, not from mmap
  mallopt(M_TRIM_THRESHOLD, 1 << 30);    // and the heap not trimmed below 1 GiB of free space
#endif
}

namespace {

constexpr const char* kTunable = "glibc.malloc.hugetlb";

std::string tunables() {
  const char* t = std::getenv("GLIBC_TUNABLES");
  return t ? t : "";
}

std::string thp_mode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(in, line);
  const size_t open = line.find('['), close = line.find(']');
  return open != std::string::npos && close > open ? line.substr(open + 1, close - open - 1) : "";
}

bool glibc_can_ask() {
#if defined(__GLIBC__)
  int major = 0, minor = 0;
  std::istringstream v(gnu_get_libc_version());
  char dot;
  v >> major >> dot >> minor;
  return major > 2 || (major == 2 && minor >= 35);
#else
  return false;
#endif
}

}  // namespace

void use_huge_pages(char** argv) {
  const char* opt = std::getenv("MPATH_HUGE_PAGES");
  if (opt && std::strcmp(opt, "0") == 0) return;
  const std::string current = tunables();
  if (current.find(kTunable) != std::string::npos || thp_mode() != "madvise" || !glibc_can_ask()) return;
  const std::string wanted = (current.empty() ? "" : current + ":") + kTunable + "=1";
  if (setenv("GLIBC_TUNABLES", wanted.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // The exec failed: run on as this process is (only slower), with the
  // environment as it was.
  if (current.empty())
    unsetenv("GLIBC_TUNABLES");
  else
    setenv("GLIBC_TUNABLES", current.c_str(), 1);
}

std::string transparent_huge_pages() { return thp_mode(); }

bool malloc_asks_for_huge_pages() {
  return glibc_can_ask() && tunables().find(std::string(kTunable) + "=1") != std::string::npos;
}

}  // namespace mpath
