#include "atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "error.h"
#include "interrupt.h"

namespace mpath {

namespace fs = std::filesystem;

fs::path temporary_path(const fs::path& final_path) {
  return final_path.parent_path() / fmt::format(".{}.tmp.{}", final_path.filename().string(), getpid());
}

void write_text_file(const fs::path& path, const std::string& text) {
  AtomicFile file(path);
  file.stream() << text;
  file.commit();
}

void commit_temporary(const fs::path& temp, const fs::path& final_path) {
  std::error_code ec;
  fs::rename(temp, final_path, ec);
  if (ec) {
    std::error_code ignored;  // the rename's error is the one to report
    fs::remove(temp, ignored);
    throw InputError(fmt::format("{}: cannot move finished file into place: {}", final_path.string(), ec.message()));
  }
}

AtomicFile::AtomicFile(const fs::path& final_path) : AtomicFile(final_path, temporary_path(final_path)) {}

// Temporaries of `final_path` left by a run that was killed (SIGKILL gives
// no chance to clean up): `.NAME.tmp.PID` whose process is gone.
void remove_stale_temporaries(const fs::path& final_path) {
  std::string prefix = ".";
  prefix += final_path.filename().string();
  prefix += ".tmp.";
  std::error_code ec;
  const fs::path dir = final_path.parent_path().empty() ? fs::path(".") : final_path.parent_path();
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string pid_text = name.substr(prefix.size());
    if (pid_text.empty() || pid_text.find_first_not_of("0123456789") != std::string::npos || pid_text.size() > 9) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(pid_text));
    if (pid == getpid() || pid <= 0) continue;
    if (kill(pid, 0) == -1 && errno == ESRCH) {
      std::error_code ignored;
      fs::remove(it->path(), ignored);
    }
  }
}

AtomicFile::AtomicFile(const fs::path& final_path, const fs::path& temp_path) : final_(final_path), temp_(temp_path) {
  remove_stale_temporaries(final_path);
  interrupt_slot_ = remember_temporary(temp_);
  out_.open(temp_, std::ios::binary | std::ios::trunc);
  if (!out_) throw InputError(fmt::format("{}: cannot create file: {}", temp_.string(), std::strerror(errno)));
}

AtomicFile::~AtomicFile() {
  forget_temporary(interrupt_slot_);
  if (!committed_) {
    out_.close();
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicFile::commit() {
  out_.flush();
  const bool ok = out_.good();
  const int err = errno;
  out_.close();
  if (!ok || out_.fail()) {
    std::error_code ec;
    fs::remove(temp_, ec);
    committed_ = true;
    throw InputError(fmt::format("{}: writing failed ({}); nothing was written under that name", final_.string(),
                                 err ? std::strerror(err) : "stream error"));
  }
  commit_temporary(temp_, final_);
  committed_ = true;
}

}  // namespace mpath
